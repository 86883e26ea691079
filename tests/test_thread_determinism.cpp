// Reproducibility across backends and thread counts: a short compression (then partial
// decompression) of a small polydisperse gas gives bitwise identical trajectories and
// measurements whatever the number of threads, for every family of contact laws that keeps
// per-contact history: frictionless, frictional (tangential spring), frictional with rolling
// and torsion springs, hysteretic (delta_max) with friction, and Hertz-Mindlin. This holds by
// construction: every particle sums its own forces in neighbour-list order, each contact's
// history is advanced by its owner only, cells are sorted, and diagnostics are summed in
// fixed blocks.
// The reference run uses one thread: on the Serial backend when it is enabled, and on the
// OpenMP backend inside a one-thread partition of its pool (OpenMP::partition_master), so the
// comparison also exists in builds with a single host backend. The compared run uses the
// default host space with all the threads the test was started with (ctest: 1 and 2).
#include <gtest/gtest.h>

#include <type_traits>
#include <vector>

#ifdef KOKKOS_ENABLE_OPENMP
#include <omp.h>
#endif

#include "kernels/contact_model.hpp"
#include "kernels/dem_system.hpp"
#include "scenarios/common/packing.hpp"
#include "test_support.hpp"

using namespace granular;

namespace {

struct Trace {
  std::vector<double> x, v, w, diag;
  int concurrency = 0;  // threads of the space the run used
  int slabs = 0;        // slabs of the host force kernel at the end (rounds of 3 in parallel)
};

template <class Exec, class Model>
Trace run_short_compression(const Model& model, int count, long steps) {
  GasSpec g;
  g.count = count, g.diameter_min = 1, g.diameter_max = 3, g.density = 2000, g.phi = 0.45;
  g.speed = 0.01, g.seed = 3;
  PeriodicBox box;
  const HostParticles h = random_gas(g, box);
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.2, prm.damping.translational = 100;
  prm.damping.rotational = 20;
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
  Trace t;
#ifdef KOKKOS_ENABLE_OPENMP
  // OpenMP::concurrency() is the hardware's count; the pool size is what kernels use.
  if constexpr (std::is_same_v<Exec, Kokkos::OpenMP>)
    t.concurrency = Kokkos::OpenMP::impl_thread_pool_size();
  else
#endif
    t.concurrency = Exec().concurrency();
  auto record = [&] {
    const Measurements m = sys.measure();
    for (double d : {m.ekin, m.epot, m.pressure, m.stress[3], m.z, m.z_corrected, m.max_overlap})
      t.diag.push_back(d);
  };
  // Compress to phi ~ 0.65 (contacts load, springs stretch and slide), then expand a little
  // (contacts unload and open: hysteretic branches, springs released).
  sys.set_strain_rate(-1.5e-2, -1.5e-2, -1.5e-2);
  for (int k = 0; k < 8; ++k) {
    sys.step(steps / 10);
    record();
  }
  EXPECT_GT(sys.measure().contacts, count / 4);  // there are contacts to sum
  sys.set_strain_rate(5e-3, 5e-3, 5e-3);
  for (int k = 0; k < 2; ++k) {
    sys.step(steps / 10);
    record();
  }
  EXPECT_GT(sys.neighbor_list().builds(), 2);  // rebuilds happened inside the compared window
  t.slabs = sys.neighbor_list().num_slabs();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().v);
  auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().w);
  t.x.assign(x.data(), x.data() + x.size());
  t.v.assign(v.data(), v.data() + v.size());
  if (Model::rotations) t.w.assign(w.data(), w.data() + w.size());
  return t;
}

#ifdef KOKKOS_ENABLE_OPENMP
// Runs f() with the OpenMP backend restricted to one thread: a single partition of size
// one of the pool. partition_master partitions only when nested parallelism is allowed.
template <class F>
Trace in_one_openmp_thread(const F& f) {
  Trace t;
  const int levels = omp_get_max_active_levels();
  omp_set_max_active_levels(2);
  Kokkos::OpenMP::partition_master([&](int, int) { t = f(); }, 1, 1);
  omp_set_max_active_levels(levels);
  return t;
}
#endif

using granular::testing::bitwise_equal;

void expect_identical(const Trace& a, const Trace& b, const char* what) {
  EXPECT_TRUE(bitwise_equal(a.x, b.x)) << what << ": positions differ";
  EXPECT_TRUE(bitwise_equal(a.v, b.v)) << what << ": velocities differ";
  EXPECT_TRUE(bitwise_equal(a.w, b.w)) << what << ": angular velocities differ";
  EXPECT_TRUE(bitwise_equal(a.diag, b.diag)) << what << ": diagnostics differ";
}

// `slabs` (if given): the number of slabs of the host force kernel at the end of the run.
template <class Model>
void expect_thread_count_independent(const Model& model, int count = 400, long steps = 2500,
                                     int* slabs = nullptr) {
  using Host = Kokkos::DefaultHostExecutionSpace;
  const Trace parallel = run_short_compression<Host>(model, count, steps);
  if (slabs) *slabs = parallel.slabs;
  if (Model::rotations) {
    double spin = 0;
    for (double w : parallel.w) spin = std::max(spin, std::fabs(w));
    EXPECT_GT(spin, 0.0) << "nothing rotates: the rotational history is not exercised";
  }
#ifdef KOKKOS_ENABLE_SERIAL
  expect_identical(run_short_compression<Kokkos::Serial>(model, count, steps), parallel,
                   "Serial vs default host space");
#endif
#ifdef KOKKOS_ENABLE_OPENMP
  const Trace one = in_one_openmp_thread(
      [&] { return run_short_compression<Kokkos::OpenMP>(model, count, steps); });
  ASSERT_EQ(one.concurrency, 1) << "the one-thread partition did not take effect";
  if constexpr (std::is_same_v<Host, Kokkos::OpenMP>)
    expect_identical(one, parallel, "OpenMP one thread vs all threads");
  else
    expect_identical(one, run_short_compression<Kokkos::OpenMP>(model, count, steps),
                     "OpenMP one thread vs all threads");
#endif
  // Run to run on the parallel space, too.
  expect_identical(run_short_compression<Host>(model, count, steps), parallel, "run to run");
}

}  // namespace

TEST(ThreadDeterminism, SerialAndHostParallelTrajectoriesAreBitwiseIdentical) {
  expect_thread_count_independent(frictionless_linear(1e5, 1000), 700, 2500);
}

TEST(ThreadDeterminism, FrictionalTangentialHistoryIsThreadCountIndependent) {
  using Model = ContactModel<LinearNormal, CoulombTangential>;
  expect_thread_count_independent(
      Model{LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.4), {}});
}

TEST(ThreadDeterminism, RollingAndTorsionHistoryIsThreadCountIndependent) {
  using Model = ContactModel<LinearNormal, CoulombTangential, RollingTorsion>;
  expect_thread_count_independent(Model{LinearNormal::uniform(1e5, 1000),
                                        CoulombTangential::uniform(8e4, 200, 0.5, 0.5),
                                        RollingTorsion::uniform({2e4, 50, 0.1, 2e4, 50, 0.1})});
}

TEST(ThreadDeterminism, HystereticAdhesiveHistoryIsThreadCountIndependent) {
  using Model = ContactModel<HystereticNormal, CoulombTangential>;
  const double k2 = 15e4;
  expect_thread_count_independent(Model{HystereticNormal::uniform(0.666 * k2, k2, 0.5 * k2, 1000),
                                        CoulombTangential::uniform(0.2866 * k2, 200, 0.5, 0.5),
                                        {}});
}

TEST(ThreadDeterminism, HertzMindlinHistoryIsThreadCountIndependent) {
  using Model = ContactModel<HertzNormal, CoulombTangential>;
  const double Gp = 29e3, nu = 0.2;
  expect_thread_count_independent(
      Model{{PairTable<HertzNormal::Params>::uniform(HertzNormal::stiffness_form(Gp, nu, 1000))},
            CoulombTangential::uniform(2 * Gp / (2 - nu), 20, 0.5, 0.5,
                                       CoulombTangential::MindlinPairDiameter),
            {}});
}

// Enough particles for several slabs per round of the host force kernel, so that threads
// really share a round and scatter reactions into each other's neighbour slabs.
TEST(ThreadDeterminism, FrictionalPackingOverManySlabsIsThreadCountIndependent) {
  using Model = ContactModel<LinearNormal, CoulombTangential>;
  int slabs = 0;
  expect_thread_count_independent(
      Model{LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.4), {}},
      3000, 1500, &slabs);
  EXPECT_GE(slabs, 6);
}
