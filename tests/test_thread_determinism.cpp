// Reproducibility across backends and thread counts: a short compression of a small
// polydisperse gas gives bitwise identical trajectories and measurements on Serial (one
// thread) and on OpenMP with however many threads the test runs with. This holds by
// construction: every particle sums its own forces in neighbour-list order, cells are
// sorted, and diagnostics are summed in fixed blocks.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "kernels/contact_model.hpp"
#include "kernels/dem_system.hpp"
#include "scenarios/packing.hpp"

using namespace granular;

#if defined(KOKKOS_ENABLE_OPENMP) && defined(KOKKOS_ENABLE_SERIAL)
namespace {

struct Trace {
  std::vector<double> x, v, diag;
};

template <class Exec>
Trace run_short_compression() {
  GasSpec g;
  g.count = 700, g.diameter_min = 1, g.diameter_max = 3, g.density = 2000, g.phi = 0.45;
  g.speed = 0.01, g.seed = 3;
  PeriodicBox box;
  const HostParticles h = random_gas(g, box);
  const auto model = frictionless_linear(1e5, 1000);
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.2, prm.damping.translational = 100;
  DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(h), box, model, prm);
  sys.set_strain_rate(-1.5e-2, -1.5e-2, -1.5e-2);  // to phi ~ 0.64
  Trace t;
  for (int k = 0; k < 10; ++k) {
    sys.step(200);
    const Measurements m = sys.measure();
    for (double d : {m.ekin, m.epot, m.pressure, m.stress[3], m.z, m.z_corrected, m.max_overlap})
      t.diag.push_back(d);
  }
  EXPECT_GT(sys.neighbor_list().builds(), 2);  // rebuilds happened inside the compared window
  EXPECT_GT(sys.measure().contacts, 100);      // and there are contacts to sum
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().v);
  t.x.assign(x.data(), x.data() + x.size());
  t.v.assign(v.data(), v.data() + v.size());
  return t;
}

bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace

TEST(ThreadDeterminism, SerialAndHostParallelTrajectoriesAreBitwiseIdentical) {
  const Trace serial = run_short_compression<Kokkos::Serial>();
  const Trace parallel = run_short_compression<Kokkos::OpenMP>();
  EXPECT_TRUE(bitwise_equal(serial.x, parallel.x)) << "positions differ";
  EXPECT_TRUE(bitwise_equal(serial.v, parallel.v)) << "velocities differ";
  EXPECT_TRUE(bitwise_equal(serial.diag, parallel.diag)) << "diagnostics differ";
  // Run-to-run on the parallel backend, too.
  const Trace again = run_short_compression<Kokkos::OpenMP>();
  EXPECT_TRUE(bitwise_equal(again.x, parallel.x));
}
#endif  // both host backends
