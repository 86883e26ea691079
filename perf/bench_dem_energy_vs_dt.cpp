// Speed against accuracy of the DEM integrator: energy conservation of an undamped dense
// packing (frictionless linear springs, no dashpots, no background damping) against the
// time step, and the cost of a unit of simulated time.
//
//   bench_dem_energy_vs_dt --kokkos-threads=2 [--n 4096] [--periods 100] [--cache DIR]
//                          [--fractions 0.005,0.01,...] [--out perf/results/dem_energy_vs_dt.json]
//                          [--precision double,mixed]
//
// The time step is given as a fraction of t_c = pi sqrt(m_red / k_n), the contact duration
// of the lightest pair (two smallest spheres). Each run starts from the same state (the
// throughput benchmark's dense packing plus Gaussian velocities), advances `periods` t_c of
// simulated time and samples the total energy E = E_kin + E_pot about 200 times.
// Velocity Verlet conserves a shadow energy: the relative error should scale like dt^2
// until the step crosses the stability edge dt = 2 / omega_max of the contact network,
// where the energy grows without bound; the engine's guards (non-finite energy, runaway
// overlap or energy) then stop the run and the row is recorded as "unstable".
// The engine's own time-step guard (dt <= t_c/10) is lifted here, since the scan goes past it.
// --precision double,mixed: a row per precision and time step, both on the two-pass kernel
// (DemParams::mixed_precision reads fixed-point positions in the force pass,
// docs/mixed_precision.md); the default, double alone, runs the host's one-pass kernel.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "command_line.hpp"
#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "core/run/rng.hpp"
#include "dense_packing.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "machine_info.hpp"

using namespace granular;
using Exec = Kokkos::DefaultExecutionSpace;

namespace {

constexpr double kKn = 1e5;  // normal stiffness, ug/us^2 (= 1e8 N/m)

// Largest angular frequency of the normal-spring network of the initial state: power
// iteration on the mass-weighted stiffness matrix M^-1/2 K M^-1/2 (normal springs only;
// the geometric term f/r is below 1 % here), and the Gershgorin bound on it.
struct NetworkFrequency {
  double omega_power = 0, omega_gershgorin = 0;
  long contacts = 0;
};

NetworkFrequency network_frequency(const HostParticles& h, const PeriodicBox& box) {
  const int n = h.size();
  std::vector<double> m(n);
  for (int i = 0; i < n; ++i)
    m[i] = h.density[i] * 4.0 / 3.0 * M_PI * h.radius[i] * h.radius[i] * h.radius[i];
  struct Pair {
    int i, j;
    double nx[3];
  };
  std::vector<Pair> pairs;
  std::vector<double> row(n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      double d[3] = {box.min_image(h.x[j] - h.x[i], 0), box.min_image(h.y[j] - h.y[i], 1),
                     box.min_image(h.z[j] - h.z[i], 2)};
      const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (r >= h.radius[i] + h.radius[j]) continue;
      pairs.push_back({i, j, {d[0] / r, d[1] / r, d[2] / r}});
      const double off = kKn / std::sqrt(m[i] * m[j]);
      row[i] += kKn / m[i] + off;
      row[j] += kKn / m[j] + off;
    }
  NetworkFrequency out;
  out.contacts = static_cast<long>(pairs.size());
  out.omega_gershgorin = std::sqrt(*std::max_element(row.begin(), row.end()));
  // Power iteration on D = M^-1/2 K M^-1/2 (positive semi-definite): y = D x.
  std::vector<double> x(3 * n), y(3 * n);
  Stream rng(7, 0);
  for (double& v : x) v = rng.uniform(-1, 1);
  double lambda = 0;
  for (int it = 0; it < 500; ++it) {
    std::fill(y.begin(), y.end(), 0.0);
    for (const Pair& p : pairs) {
      // u = x_i/sqrt(m_i) - x_j/sqrt(m_j); spring force k (n.u) n.
      const double si = 1 / std::sqrt(m[p.i]), sj = 1 / std::sqrt(m[p.j]);
      double nu = 0;
      for (int d = 0; d < 3; ++d) nu += p.nx[d] * (x[3 * p.i + d] * si - x[3 * p.j + d] * sj);
      for (int d = 0; d < 3; ++d) {
        y[3 * p.i + d] += kKn * nu * p.nx[d] * si;
        y[3 * p.j + d] -= kKn * nu * p.nx[d] * sj;
      }
    }
    double norm = 0, dot = 0;
    for (int k = 0; k < 3 * n; ++k) norm += y[k] * y[k], dot += x[k] * y[k];
    norm = std::sqrt(norm);
    double xx = 0;
    for (int k = 0; k < 3 * n; ++k) xx += x[k] * x[k];
    lambda = dot / xx;
    for (int k = 0; k < 3 * n; ++k) x[k] = y[k] / norm;
  }
  out.omega_power = std::sqrt(lambda);
  return out;
}

struct Options {
  int n = 4096;
  double periods = 100;      // simulated time in units of t_c
  double v_sigma = 5e-5;     // mm/us = 0.05 m/s per component, as in the peer packings
  int samples_target = 200;  // energy samples per run
  std::string cache_dir = "perf_cache", out = "perf/results/dem_energy_vs_dt.json";
  std::string precisions = "double";
  std::string fractions =
      "0.005,0.01,0.02,0.03,0.05,0.07,0.1,0.14,0.2,0.25,0.3,0.35,0.4,0.45,0.5,0.55,0.6,0.65,"
      "0.7,0.8";
};

// The options in order; a malformed value throws. Returns false on an unknown option (named
// on stderr); Kokkos' own options are left to Kokkos.
bool parse_options(int argc, char** argv, Options& o) {
  return perf::read_options(argc, argv, [&](const std::string& a, const auto& value) {
    if (a == "--n")
      o.n = std::stoi(value());
    else if (a == "--periods")
      o.periods = std::stod(value());
    else if (a == "--fractions")
      o.fractions = value();
    else if (a == "--cache")
      o.cache_dir = value();
    else if (a == "--out")
      o.out = value();
    else if (a == "--precision")
      o.precisions = value();
    else if (a == "--samples")
      o.samples_target = std::stoi(value());
    else
      return false;
    return true;
  });
}

// The throughput benchmark's dense packing with Gaussian velocities of zero net momentum.
HostParticles initial_state(const Options& o, PeriodicBox& box) {
  HostParticles host = perf::dense_packing(o.n, box, o.cache_dir);
  const int n = host.size();
  for (int i = 0; i < n; ++i) {
    Stream s(12345, static_cast<std::uint64_t>(i));
    host.vx[i] = o.v_sigma * s.normal(), host.vy[i] = o.v_sigma * s.normal(),
    host.vz[i] = o.v_sigma * s.normal();
  }
  double p[3] = {0, 0, 0}, mt = 0;
  for (int i = 0; i < n; ++i) {
    const double m = host.density[i] * std::pow(host.radius[i], 3);
    p[0] += m * host.vx[i], p[1] += m * host.vy[i], p[2] += m * host.vz[i], mt += m;
  }
  for (int i = 0; i < n; ++i)
    host.vx[i] -= p[0] / mt, host.vy[i] -= p[1] / mt, host.vz[i] -= p[2] / mt;
  return host;
}

// The time scales of the initial state: t_c of the lightest pair, undamped (pi sqrt(m_red /
// k)), and the network's largest frequency.
struct TimeScales {
  double omega_pair = 0, tc = 0;
  NetworkFrequency net;
};

TimeScales time_scales(const HostParticles& host, const PeriodicBox& box) {
  const int n = host.size();
  std::vector<double> masses(n);
  for (int i = 0; i < n; ++i)
    masses[i] = host.density[i] * 4.0 / 3.0 * M_PI * std::pow(host.radius[i], 3);
  std::partial_sort(masses.begin(), masses.begin() + 2, masses.end());
  const double m_red = masses[0] * masses[1] / (masses[0] + masses[1]);
  TimeScales ts;
  ts.omega_pair = std::sqrt(kKn / m_red);
  ts.tc = M_PI / ts.omega_pair;
  ts.net = network_frequency(host, box);
  std::cerr << "t_c = " << ts.tc << " us; stability edge dt/t_c: pair "
            << 2 / (ts.omega_pair * ts.tc) << ", network (power iteration) "
            << 2 / (ts.net.omega_power * ts.tc) << ", Gershgorin bound "
            << 2 / (ts.net.omega_gershgorin * ts.tc) << "\n";
  return ts;
}

// The result's members ahead of its rows: the set-up, its time scales and the time steps the
// scenes and benchmarks use, as fractions of t_c.
Json result_header(const Options& o, int n, const TimeScales& ts) {
  const double tc = ts.tc;
  Json result = Json::object();
  result["benchmark"] = "dem_energy_vs_dt";
  result["machine"] = perf::machine_info();
  result["N"] = n;
  result["physics"] =
      "frictionless linear spring k_n 1e5 ug/us^2 (1e8 N/m), no dashpot, no background "
      "damping, velocity Verlet";
  result["initial_state"] =
      "dense packing of bench_dem_throughput (phi 0.64, made with mu 0.1) + Gaussian "
      "velocities 0.05 m/s per component";
  result["contact_time_us"] = tc;
  result["simulated_time_us"] = o.periods * tc;
  result["simulated_time_in_tc"] = o.periods;
  result["omega_pair_per_us"] = ts.omega_pair;
  result["omega_max_network_per_us"] = ts.net.omega_power;
  result["omega_gershgorin_bound_per_us"] = ts.net.omega_gershgorin;
  result["initial_contacts"] = ts.net.contacts;
  result["edge_fraction_pair"] = 2 / (ts.omega_pair * tc);
  result["edge_fraction_network"] = 2 / (ts.net.omega_power * tc);
  result["edge_fraction_gershgorin"] = 2 / (ts.net.omega_gershgorin * tc);
  result["engine_guard_fraction"] = DemParams{}.dt_guard;  // the default refuses dt > t_c/10
  Json defaults = Json::array();
  Json d = Json::object();
  d["what"] = "scenes (isotropic_compression, elastic_moduli): dt = 0.004 us";
  d["dt_us"] = 0.004;
  d["fraction"] = 0.004 / tc;
  defaults.push(d);
  Json e = Json::object();
  e["what"] = "benchmarks and peer decks: dt = 0.0045 us (t_c/50 of the damped pair)";
  e["dt_us"] = 0.0045;
  e["fraction"] = 0.0045 / tc;
  defaults.push(e);
  result["default_time_steps"] = defaults;
  return result;
}

// One run at a time step: the energy error sampled along it, its extremes and its cost.
struct EnergyRun {
  long steps = 0, done = 0;
  std::vector<double> t_s, e_s;  // time in t_c, relative energy error
  double wall = 0, e0 = 0, ekin0 = 0, max_err = 0, ekin_max = 0;
  std::string status = "stable", message;
};

// Advances the initial state `steps` steps of dt = prm.dt, sampling the energy every `every`
// steps (the samples untimed); a guard that trips marks the run unstable.
EnergyRun integrate(const HostParticles& host, const PeriodicBox& box, const DemParams& prm,
                    long steps, long every, double tc) {
  const FrictionlessLinear model = frictionless_linear(kKn, 0.0);
  EnergyRun r;
  r.steps = steps;
  try {
    DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(host), box, model, prm);
    const Measurements m0 = sys.measure();
    r.e0 = m0.ekin + m0.epot, r.ekin0 = m0.ekin;
    r.t_s.push_back(0), r.e_s.push_back(0);
    while (r.done < steps) {
      const long k = std::min(every, steps - r.done);
      Kokkos::fence();
      Kokkos::Timer timer;
      sys.step(k);
      Kokkos::fence();
      r.wall += timer.seconds();
      r.done += k;
      const Measurements m = sys.measure();
      const double err = (m.ekin + m.epot - r.e0) / r.e0;
      r.t_s.push_back(sys.time() / tc), r.e_s.push_back(err);
      if (std::isfinite(err)) r.max_err = std::max(r.max_err, std::abs(err));
      if (std::isfinite(m.ekin)) r.ekin_max = std::max(r.ekin_max, m.ekin);
      sys.check_health(m);
      if (!(std::abs(err) < 1.0)) throw PhysicsError("total energy changed by more than 100 %");
    }
  } catch (const PhysicsError& e) {
    r.status = "unstable";
    r.message = e.what();
  }
  return r;
}

// The row of a run (and its line on stdout).
Json row_json(const EnergyRun& r, double f, const DemParams& prm, int n, double tc) {
  const double dt = prm.dt;
  Json row = Json::object();
  row["fraction"] = f;
  row["precision"] = prm.mixed_precision ? "mixed" : "double";
  row["force_kernel"] = prm.two_pass_forces ? "two-pass" : "default";
  row["dt_us"] = dt;
  row["steps"] = r.steps;
  row["status"] = r.status;
  if (!r.message.empty()) row["stopped_by"] = r.message;
  row["steps_done"] = r.done;
  row["initial_energy"] = r.e0;
  row["initial_kinetic_energy"] = r.ekin0;
  row["max_kinetic_energy"] = r.ekin_max;
  row["max_relative_energy_error"] = r.max_err;
  // The same error against the largest kinetic energy of the run (the energy in motion).
  if (r.ekin_max > 0) row["max_energy_error_over_max_kinetic"] = r.max_err * r.e0 / r.ekin_max;
  row["final_relative_energy_error"] = r.e_s.back();
  row["wall_s"] = r.wall;
  if (r.done > 0) {
    row["cost_s_per_us_simulated"] = r.wall / (r.done * dt);
    row["cost_s_per_tc_simulated"] = r.wall / (r.done * dt) * tc;
    row["particle_steps_per_s"] = static_cast<double>(n) * r.done / r.wall;
  }
  row["time_in_tc"] = r.t_s;
  row["relative_energy_error"] = r.e_s;
  std::cout << (prm.mixed_precision ? "mixed " : "") << "dt/t_c " << f << ": " << r.status
            << ", max |dE|/E " << r.max_err << ", " << r.done << "/" << r.steps << " steps, "
            << r.wall << " s";
  if (r.done > 0) std::cout << ", " << r.wall / (r.done * dt) * tc << " s per t_c";
  std::cout << "\n";
  return row;
}

// A row per time-step fraction, each run from the same initial state.
Json run_fractions(const Options& o, const HostParticles& host, const PeriodicBox& box, double tc) {
  Json rows = Json::array();
  const std::vector<std::string> precisions = perf::word_list(o.precisions);
  for (const std::string& p : precisions)
    if (p != "double" && p != "mixed")
      throw std::runtime_error("--precision takes double and/or mixed, not " + p);
  const bool compared = o.precisions != "double";
  for (const std::string& precision : precisions)
    for (const double f : perf::number_list(o.fractions)) {
      DemParams prm = perf::bench_params();
      prm.dt = f * tc;
      prm.dt_guard = 1e9;     // scan beyond the engine's t_c/10 guard on purpose
      prm.max_overlap = 0.5;  // runaway-overlap guard, as in the scenes
      prm.two_pass_forces = compared;
      prm.mixed_precision = precision == "mixed";
      const long steps = std::max(1L, std::lround(o.periods / f));
      const long every = std::max(1L, steps / o.samples_target);
      const EnergyRun r = integrate(host, box, prm, steps, every, tc);
      rows.push(row_json(r, f, prm, host.size(), tc));
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
    const HostParticles host = initial_state(o, box);
    const TimeScales ts = time_scales(host, box);
    Json result = result_header(o, host.size(), ts);
    result["rows"] = run_fractions(o, host, box, ts.tc);
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
