// The accuracy cost of the mixed-precision force pass (DemParams::mixed_precision: positions
// read as 32-bit fixed-point fractions of the box, forces in double; docs/mixed_precision.md),
// on the benchmarks' dense frictional packing:
//
//   bench_mixed_precision --kokkos-threads=2 [--n 32768] [--steps 4000] [--cache perf_cache]
//                         [--strains 1e-7,1e-6,1e-5,1e-4] [--out perf/results/mixed_precision.json]
//
// 1. Trajectory cross-check: the packing with Gaussian velocities stepped `steps` steps of the
//    peer benchmark's frictional law (no background damping) in double, in mixed precision,
//    and in double from positions moved by up to half a fixed-point step (the yardstick: how
//    far any difference of that size grows in the same time). Kinetic energy, pressure and the
//    largest position difference sampled along the way.
// 2. Moduli probe: the packing at rest relaxed under background damping, then strained
//    isotropically (bulk modulus K = dp / (3 eps)) or in pure shear (e_xx = eps, e_yy = -eps:
//    G = d(s_xx - s_yy) / (4 eps)) within 200 steps and relaxed again, at each strain amplitude,
//    in both precisions. The stress change is taken against the same run without strain (the
//    packing still relaxes: at 1e-7 its drift is larger than the response). The stresses are
//    measured in double from the positions each run reached.
// The energy drift against the time step is bench_dem_energy_vs_dt's --precision double,mixed.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "command_line.hpp"
#include "core/io/output.hpp"
#include "core/run/rng.hpp"
#include "dense_packing.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "machine_info.hpp"

using namespace granular;
using Exec = Kokkos::DefaultExecutionSpace;

namespace {

// The peer benchmark's frictional law (perf/bench_dem_throughput.cpp "friction").
using Frictional = ContactModel<LinearNormal, CoulombTangential>;
Frictional frictional() {
  return {LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 500, 0.5, 0.5), {}};
}

struct Options {
  int n = 32768;
  long steps = 4000;
  std::string cache_dir = "perf_cache", out = "perf/results/mixed_precision.json";
  std::string strains = "1e-7,1e-6,1e-5,1e-4";
};

bool parse_options(int argc, char** argv, Options& o) {
  return perf::read_options(argc, argv, [&](const std::string& a, const auto& value) {
    if (a == "--n")
      o.n = std::stoi(value());
    else if (a == "--steps")
      o.steps = std::stol(value());
    else if (a == "--cache")
      o.cache_dir = value();
    else if (a == "--out")
      o.out = value();
    else if (a == "--strains")
      o.strains = value();
    else
      return false;
    return true;
  });
}

DemParams params(bool mixed) {
  DemParams prm = perf::bench_params();
  prm.two_pass_forces = true;  // both precisions run the same kernel
  prm.mixed_precision = mixed;
  return prm;
}

std::vector<double> positions(const DemSystem<Exec, Frictional>& sys) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
  auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().id);
  std::vector<double> out(3 * x.extent(0));  // by identity: the arrays are sorted by cell
  for (size_t i = 0; i < x.extent(0); ++i)
    for (int d = 0; d < 3; ++d) out[3 * id(i) + d] = x(i, d);
  return out;
}

double max_separation(const std::vector<double>& a, const std::vector<double>& b,
                      const PeriodicBox& box) {
  double m = 0;
  for (size_t k = 0; k < a.size(); ++k)
    m = std::max(m, std::fabs(box.min_image(a[k] - b[k], static_cast<int>(k % 3))));
  return m;
}

// Part 1: three runs from the same moving packing, sampled 20 times.
Json trajectory_cross_check(const Options& o, HostParticles host, const PeriodicBox& box) {
  for (int i = 0; i < host.size(); ++i) {
    Stream s(12345, static_cast<std::uint64_t>(i));
    host.vx[i] = 5e-5 * s.normal(), host.vy[i] = 5e-5 * s.normal(), host.vz[i] = 5e-5 * s.normal();
  }
  HostParticles moved = host;  // up to half a fixed-point step in each coordinate
  for (int i = 0; i < host.size(); ++i) {
    Stream s(777, static_cast<std::uint64_t>(i));
    moved.x[i] += (s.uniform() - 0.5) * box.len[0] / kFixedPointSteps;
    moved.y[i] += (s.uniform() - 0.5) * box.len[1] / kFixedPointSteps;
    moved.z[i] += (s.uniform() - 0.5) * box.len[2] / kFixedPointSteps;
  }
  DemSystem<Exec, Frictional> dbl(Particles<Exec>::from_host(host), box, frictional(),
                                  params(false));
  DemSystem<Exec, Frictional> mix(Particles<Exec>::from_host(host), box, frictional(),
                                  params(true));
  DemSystem<Exec, Frictional> yard(Particles<Exec>::from_host(moved), box, frictional(),
                                   params(false));
  Json rows = Json::array();
  const long every = std::max(1L, o.steps / 20);
  for (long done = 0; done <= o.steps; done += every) {
    if (done > 0) dbl.step(every), mix.step(every), yard.step(every);
    const Measurements md = dbl.measure(), mm = mix.measure(), my = yard.measure();
    const std::vector<double> xd = positions(dbl);
    Json r = Json::object();
    r["step"] = done;
    r["ekin_double"] = md.ekin;
    r["ekin_relative_difference_mixed"] = (mm.ekin - md.ekin) / md.ekin;
    r["ekin_relative_difference_moved_half_step"] = (my.ekin - md.ekin) / md.ekin;
    r["pressure_double"] = md.pressure;
    r["pressure_relative_difference_mixed"] = (mm.pressure - md.pressure) / md.pressure;
    r["pressure_relative_difference_moved_half_step"] = (my.pressure - md.pressure) / md.pressure;
    r["max_position_difference_mixed"] = max_separation(positions(mix), xd, box);
    r["max_position_difference_moved_half_step"] = max_separation(positions(yard), xd, box);
    std::cout << "step " << done << ": dE_kin/E_kin mixed " << (mm.ekin - md.ekin) / md.ekin
              << ", moved " << (my.ekin - md.ekin) / md.ekin << "\n";
    rows.push(r);
  }
  return rows;
}

// One probe: relaxed at rest, strained by eps (isotropic or pure shear) over 200 steps (none
// when eps = 0: the baseline), relaxed again; returns the stresses before and after, and the
// strain reached.
struct Probe {
  Measurements before, after;
  double strain = 0;
};

Probe probe(HostParticles host, const PeriodicBox& box, bool mixed, bool shear, double eps) {
  for (int i = 0; i < host.size(); ++i) host.vx[i] = host.vy[i] = host.vz[i] = 0.0;
  DemParams prm = params(mixed);
  prm.damping.translational = 2000;  // relaxation time m/gamma ~ 4 us (900 steps) for d = 2
  prm.damping.rotational = 200;
  DemSystem<Exec, Frictional> sys(Particles<Exec>::from_host(host), box, frictional(), prm);
  sys.step(3000);
  Probe p;
  p.before = sys.measure();
  const long ramp = 200;
  const double rate = eps / (ramp * prm.dt);
  if (shear)
    sys.set_strain_rate(rate, -rate, 0.0);
  else
    sys.set_strain_rate(-rate, -rate, -rate);
  sys.step(ramp);
  sys.set_strain_rate(0, 0, 0);
  sys.step(2000);
  p.after = sys.measure();
  // The engine's strain: each step multiplies a length by (1 + rate dt).
  p.strain = shear ? std::pow(1 + rate * prm.dt, ramp) - 1 : 1 - std::pow(1 - rate * prm.dt, ramp);
  return p;
}

// The modulus of a probe against the baseline run: stresses are positive in compression, so
// stretching x and shortening y lowers s_xx - s_yy.
double modulus(const Probe& p, const Probe& base, bool shear) {
  const Measurements &m = p.after, &b = base.after;
  return shear ? -((m.stress[0] - m.stress[1]) - (b.stress[0] - b.stress[1])) / (4 * p.strain)
               : (m.pressure - b.pressure) / (3 * p.strain);
}

Json moduli_probe(const Options& o, const HostParticles& host, const PeriodicBox& box) {
  Json rows = Json::array();
  const Probe base[2] = {probe(host, box, false, false, 0.0), probe(host, box, true, false, 0.0)};
  for (const bool shear : {false, true})
    for (const double eps : perf::number_list(o.strains)) {
      const double d = modulus(probe(host, box, false, shear, eps), base[0], shear);
      const double m = modulus(probe(host, box, true, shear, eps), base[1], shear);
      Json r = Json::object();
      r["modulus"] = shear ? "G (pure shear)" : "K (isotropic)";
      r["strain"] = eps;
      r["double"] = d;
      r["mixed"] = m;
      r["relative_difference"] = (m - d) / d;
      r["pressure_before_double"] = base[0].before.pressure;
      r["pressure_before_mixed"] = base[1].before.pressure;
      r["pressure_drift_unstrained_double"] = base[0].after.pressure - base[0].before.pressure;
      std::cout << (shear ? "G" : "K") << " at strain " << eps << ": double " << d << ", mixed "
                << m << " (" << (m - d) / d << ")\n";
      rows.push(r);
    }
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::initialize(argc, argv);
  int rc = 0;
  try {
    Options o;
    if (!parse_options(argc, argv, o)) return 2;
    PeriodicBox box;
    const HostParticles host = perf::dense_packing(o.n, box, o.cache_dir);
    Json result = Json::object();
    result["benchmark"] = "mixed_precision";
    result["machine"] = perf::machine_info();
    result["N"] = host.size();
    result["box_lengths"] = std::vector<double>{box.len[0], box.len[1], box.len[2]};
    result["fixed_point_step"] = box.len[0] / kFixedPointSteps;
    result["physics"] =
        "peer benchmark friction: k_n 1e5, gamma_n 1000, k_t 8e4, gamma_t 500, mu 0.5 "
        "(mm, us, ug), dt 0.0045, two-pass kernel in both precisions";
    result["initial_state"] = "bench_dem_throughput's dense packing (phi 0.64, diameters 1-3)";
    result["trajectory"] = trajectory_cross_check(o, host, box);
    result["moduli_probe"] = moduli_probe(o, host, box);
    std::filesystem::create_directories(std::filesystem::path(o.out).parent_path());
    write_text_file(o.out, result.dump());
    std::cout << "wrote " << o.out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    rc = 1;
  }
  Kokkos::finalize();
  return rc;
}
