// The benchmarks' dense packing and time-stepping parameters, shared so that every
// benchmark times or probes the same state.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

#include "core/io/output.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/packing.hpp"

namespace granular::perf {

using BenchExec = Kokkos::DefaultExecutionSpace;

inline DemParams bench_params() {
  DemParams p;
  p.dt = 0.0045;
  p.skin = 0.2;
  p.max_overlap = 1.0;
  return p;
}

// A dense packing: random gas at phi 0.3, fast damped compression to 0.64 with a little
// friction (mu = 0.1, which jams the packing there, as in the peer's generator), short
// relaxation; cached as HDF5 so later runs (other thread counts) time the same state.
inline HostParticles dense_packing(int n, PeriodicBox& box, const std::string& cache_dir) {
  const std::string path = cache_dir + "/packing_" + std::to_string(n) + ".h5";
  if (std::filesystem::exists(path)) {
    H5Reader in(path);
    double density;
    return read_state(in, "/state", box, density);
  }
  std::cerr << "preparing a dense packing of " << n << " spheres (cached in " << path << ")\n";
  GasSpec g;
  g.count = n, g.diameter_min = 1, g.diameter_max = 3, g.density = 2000, g.phi = 0.3,
  g.seed = 12345;
  const HostParticles gas = random_gas(g, box);
  DemParams prm = bench_params();
  prm.dt = 0.004;
  prm.damping.translational = 100;
  prm.damping.rotational = 20;
  using Prep = ContactModel<LinearNormal, CoulombTangential>;
  const Prep prep{
      LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 500, 0.1, 0.1), {}};
  DemSystem<BenchExec, Prep> sys(Particles<BenchExec>::from_host(gas), box, prep, prm);
  const double rate = -2e-2 / 3;  // volumetric 2e-2 per us
  const long steps = static_cast<long>(std::log(0.64 / 0.3) / (-3 * std::log1p(rate * prm.dt)));
  sys.set_strain_rate(rate, rate, rate);
  sys.step(steps);
  sys.set_strain_rate(0, 0, 0);
  sys.step(2000);
  std::filesystem::create_directories(cache_dir);
  H5Writer out(path);
  write_state(out, "/state", sys.particles(), sys.box(), 2000.0);
  out.commit();
  H5Reader in(path);
  double density;
  return read_state(in, "/state", box, density);
}

}  // namespace granular::perf
