// Reproducibility across backends and thread counts: a short compression (then partial
// decompression) of a small polydisperse gas gives bitwise identical trajectories and
// measurements whatever the number of threads, for every family of contact laws that keeps
// per-contact history: frictionless, frictional (tangential spring), frictional with rolling
// and torsion springs, hysteretic (delta_max) with friction, and both Hertz-Mindlin laws. This
// holds by construction: every particle sums its own forces in neighbour-list order, each contact's
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

#include "core/dem/walls.hpp"
#include "core/io/scene_file.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/materials.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

struct Trace {
  std::vector<double> x, v, w, diag;
  int concurrency = 0;  // threads of the space the run used
  int slabs = 0;        // slabs of the host force kernel at the end (rounds of 3 in parallel)
};

// The threads kernels of Exec use: OpenMP::concurrency() is the hardware's count, the pool
// size is what kernels use.
template <class Exec>
int threads_of() {
#ifdef KOKKOS_ENABLE_OPENMP
  if constexpr (std::is_same_v<Exec, Kokkos::OpenMP>)
    return Kokkos::OpenMP::impl_thread_pool_size();
#endif
  return Exec().concurrency();
}

template <class Exec, class Model>
Trace run_short_compression(const Model& model, int count, long steps, bool mixed = false) {
  GasSpec g;
  g.count = count, g.diameter_min = 1, g.diameter_max = 3, g.density = 2000, g.phi = 0.45;
  g.speed = 0.01, g.seed = 3;
  PeriodicBox box;
  const HostParticles h = random_gas(g, box);
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.2, prm.damping.translational = 100;
  prm.damping.rotational = 20;
  prm.mixed_precision = mixed;
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
  Trace t;
  t.concurrency = threads_of<Exec>();
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

// The soft box's preparation in small: 5 x 5 x 4 polydisperse spheres (mean diameter 21)
// poured under gravity, with background damping, into a box of a floor and four side walls,
// with the restitution-damped Hertz-Mindlin law of the material set `mats` (walls in slot
// `wall`).
template <class Exec, class Model>
Trace run_walled_pour(const Model& model, int wall, long steps) {
  const int side = 5, layers = 4;
  const double d = 21.0, L = side * 1.1 * d;
  HostParticles h;
  h.resize(side * side * layers);
  int k = 0;
  for (int l = 0; l < layers; ++l)
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j, ++k) {
        const double wobble = 0.05 * d * std::sin(1.7 * k);
        h.x[k] = (i + 0.5) * 1.1 * d + wobble, h.y[k] = (j + 0.5) * 1.1 * d - wobble;
        h.z[k] = (l + 0.5) * 1.05 * d;
        h.radius[k] = 0.5 * d * (1 + 0.1 * std::cos(2.3 * k)), h.density[k] = 2000;
        h.vx[k] = 1e-4 * std::sin(0.7 * k), h.vy[k] = 1e-4 * std::cos(1.3 * k);
      }
  PeriodicBox box;
  for (int a = 0; a < 3; ++a) box.lo[a] = 0, box.periodic[a] = false;
  box.len[0] = box.len[1] = L, box.len[2] = (layers + 2) * 1.1 * d;
  const double mean_mass = 2000 * M_PI / 6 * d * d * d, damping_time = 2e4;
  DemParams prm;
  prm.dt = 20, prm.skin = 0.1 * d, prm.max_overlap = 0.85, prm.gravity[2] = -9.81e-9;
  prm.damping.translational = mean_mass / damping_time;
  prm.damping.rotational = 0.1 * mean_mass * d * d / damping_time;
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
  const double normals[5][3] = {{0, 0, -1}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}};
  const double points[5][3] = {{0, 0, 0}, {0, 0, 0}, {L, 0, 0}, {0, 0, 0}, {0, L, 0}};
  std::vector<WallSpec> walls;
  for (int w = 0; w < 5; ++w) {
    WallSpec ws;
    ws.name = "wall" + std::to_string(w), ws.material = wall;
    for (int a = 0; a < 3; ++a) ws.normal[a] = normals[w][a], ws.point[a] = points[w][a];
    walls.push_back(ws);
  }
  sys.set_walls(walls);
  Trace t;
  t.concurrency = threads_of<Exec>();
  for (int c = 0; c < 10; ++c) {
    sys.step(steps / 10);
    const Measurements m = sys.measure();
    for (double v : {m.ekin, m.epot, m.z, m.max_overlap}) t.diag.push_back(v);
    for (const auto& l : sys.wall_loads())
      for (double v : {l.force[0], l.force[1], l.force[2], l.contacts}) t.diag.push_back(v);
  }
  EXPECT_GT(sys.measure().contacts, h.size());               // a pile, not a gas
  EXPECT_GT(sys.wall_loads()[0].contacts, side * side / 2);  // standing on the floor
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().v);
  auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().w);
  t.x.assign(x.data(), x.data() + x.size());
  t.v.assign(v.data(), v.data() + v.size());
  t.w.assign(w.data(), w.data() + w.size());
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

// `run(Exec{})` gives a trajectory on execution space Exec; it must not depend on the space
// or on its thread count. `slabs` (if given): the number of slabs of the host force kernel at
// the end of the run.
template <class Run>
void expect_independent_of_threads(const Run& run, bool rotations, int* slabs = nullptr) {
  using Host = Kokkos::DefaultHostExecutionSpace;
  const Trace parallel = run(Host{});
  if (slabs) *slabs = parallel.slabs;
  if (rotations) {
    double spin = 0;
    for (double w : parallel.w) spin = std::max(spin, std::fabs(w));
    EXPECT_GT(spin, 0.0) << "nothing rotates: the rotational history is not exercised";
  }
#ifdef KOKKOS_ENABLE_SERIAL
  expect_identical(run(Kokkos::Serial{}), parallel, "Serial vs default host space");
#endif
#ifdef KOKKOS_ENABLE_OPENMP
  const Trace one = in_one_openmp_thread([&] { return run(Kokkos::OpenMP{}); });
  ASSERT_EQ(one.concurrency, 1) << "the one-thread partition did not take effect";
  if constexpr (std::is_same_v<Host, Kokkos::OpenMP>)
    expect_identical(one, parallel, "OpenMP one thread vs all threads");
  else
    expect_identical(one, run(Kokkos::OpenMP{}), "OpenMP one thread vs all threads");
#endif
  // Run to run on the parallel space, too.
  expect_identical(run(Host{}), parallel, "run to run");
}

template <class Model>
void expect_thread_count_independent(const Model& model, int count = 400, long steps = 2500,
                                     int* slabs = nullptr, bool mixed = false) {
  expect_independent_of_threads(
      [&](auto exec) { return run_short_compression<decltype(exec)>(model, count, steps, mixed); },
      Model::rotations, slabs);
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

// The mixed-precision force pass (fixed-point positions, DemParams::mixed_precision) keeps
// the two-pass kernel's order of summation, through a box whose lengths change every step.
TEST(ThreadDeterminism, MixedPrecisionFrictionalHistoryIsThreadCountIndependent) {
  using Model = ContactModel<LinearNormal, CoulombTangential>;
  expect_thread_count_independent(
      Model{LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.4), {}},
      400, 2500, nullptr, true);
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

// The restitution-damped Hertz-Mindlin law of the studies (its masses read by the batch and
// the near stream) over several slabs per round.
TEST(ThreadDeterminism, RestitutionHertzMindlinOverManySlabsIsThreadCountIndependent) {
  using Model = ContactModel<HertzRestitutionNormal, CoulombTangential>;
  int slabs = 0;
  expect_thread_count_independent(
      Model{HertzRestitutionNormal::uniform(7.2e4, 0.3),
            CoulombTangential::uniform(6.4e4, 0.4, 0.5, 0.5, CoulombTangential::MindlinRestitution),
            {}},
      3000, 1500, &slabs);
  EXPECT_GE(slabs, 6);
}

// The soft box's preparation (confined_compression): walls, gravity, background damping and
// the restitution-damped Hertz-Mindlin law of rubber (friction 0.5) against rigid walls.
TEST(ThreadDeterminism, WalledRubberPourUnderGravityIsThreadCountIndependent) {
  const SceneFile scene = SceneFile::parse(
      "[materials.rubber]\nyoung_modulus = 1.85\npoisson = 0.46\ndensity = 2000\n"
      "friction = 0.5\nrestitution = 0.7\n[materials.wall]\nyoung_modulus = inf\n"
      "poisson = 0.3\nfriction = 0.5\nrestitution = 0.7\n[contact]\ntangential = \"mindlin\"\n"
      "damping = \"restitution_common\"\n",
      "rubber_pour.toml");
  const MaterialSet mats = MaterialSet::read(scene);
  ASSERT_TRUE(mats.tangential);
  const int rubber = mats.slot.at("rubber"), wall = mats.slot.at("wall");
  ASSERT_EQ(rubber, 0);  // the particles' species
  with_material_model(mats, [&](const auto& model) {
    using Model = std::decay_t<decltype(model)>;
    expect_independent_of_threads(
        [&](auto exec) { return run_walled_pour<decltype(exec)>(model, wall, 6000); },
        Model::rotations);
  });
}
