// Batched chains against closed-form physics: the dispersion relation of the ordered chain,
// the exact (eigenmode) solution of the linearized chain, second-order energy error of
// velocity Verlet, the stability edge 2/omega_max, contact opening, reproducibility.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/chain/chain_exact.hpp"
#include "core/io/output.hpp"
#include "kernels/chain/chain_energy.hpp"
#include "scenarios/chains/chain_config.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

ChainSpec spec_of(int n, ChainBoundary bc, ChainForce law, double xi, std::uint64_t seed = 7) {
  ChainSpec s;
  s.beads = n, s.boundary = bc, s.force = law, s.xi = xi, s.seed = seed;
  return s;
}

template <class Space>
std::vector<double> row(
    const Kokkos::View<double**, Kokkos::LayoutRight, typename Space::memory_space>& f, int r) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), f);
  return std::vector<double>(&h(r, 0), &h(r, 0) + f.extent(1));
}

template <class Space>
ChainExactSolution exact_of(const ChainBatch<Space>& c, int r) {
  return ChainExactSolution(row<Space>(c.b, r), row<Space>(c.klin, r),
                            c.spec.boundary == ChainBoundary::Periodic);
}

Eigen::VectorXd vec(const std::vector<double>& x) {
  return Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
}

}  // namespace

TEST(ChainExact, OrderedRingEigenfrequenciesFollowTheDispersionRelation) {
  const int n = 64;
  std::vector<double> b(n, 1.0), k(n, 1.5);
  ChainExactSolution ex(b, k, true);
  std::vector<double> expect;
  for (int m = 0; m < n; ++m)
    expect.push_back(2 * std::sqrt(1.5) * std::abs(std::sin(M_PI * m / n)));
  std::sort(expect.begin(), expect.end());
  // The eigenvalues omega^2 to round-off of the largest (6). Not omega itself: the zero mode's
  // omega is the square root of a round-off-sized eigenvalue (~1e-8 on some processors).
  for (int m = 0; m < n; ++m)
    EXPECT_NEAR(ex.omega()(m) * ex.omega()(m), expect[m] * expect[m], 1e-12) << "mode " << m;
}

TEST(ChainExact, DisorderedModesAreMassOrthonormalAndEnergyIsConservedToRoundOff) {
  ChainBatch<Kokkos::DefaultHostExecutionSpace> c(
      spec_of(80, ChainBoundary::Fixed, ChainForce::Linear, 0.3), {3});
  const auto ex = exact_of(c, 0);
  const Eigen::MatrixXd& S = ex.modes();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(80, 80);
  EXPECT_LT((S.transpose() * ex.mass() * S - I).cwiseAbs().maxCoeff(), 1e-12);
  // (-K) S = M S diag(w^2)
  const Eigen::MatrixXd w2 = ex.omega().cwiseAbs2().asDiagonal();
  EXPECT_LT((-ex.stiffness() * S - ex.mass() * S * w2).cwiseAbs().maxCoeff(), 1e-11);
  ChainExactSolution moving = ex;
  Eigen::VectorXd u0 = Eigen::VectorXd::Zero(80), v0 = Eigen::VectorXd::Zero(80);
  v0(0) = 0.01, u0(40) = 0.003;
  moving.set_initial(u0, v0);
  const double e0 = moving.energy(u0, v0);
  for (double t : {1.0, 37.5, 1000.0}) {
    Eigen::VectorXd u, v;
    moving.state(t, u, v);
    EXPECT_NEAR(moving.energy(u, v) / e0, 1.0, 1e-12) << "t = " << t;
  }
}

template <class T>
class ChainTest : public ::testing::Test {};
TYPED_TEST_SUITE(ChainTest, granular::testing::ExecSpaces);

// A standing tone of a periodic ordered ring is an exact mode; Verlet turns its frequency
// w into w~ with sin(w~ dt/2) = w dt/2. Zero crossings of one bead give w~.
TYPED_TEST(ChainTest, MeasuredToneFrequenciesMatchTheDispersionRelation) {
  const int n = 64;
  const double dt = 0.05;
  const std::vector<int> tones = {3, 11, 30};  // one realization (row) each, one batch
  ChainBatch<TypeParam> c(spec_of(n, ChainBoundary::Periodic, ChainForce::Linear, 0.0), {0, 0, 0});
  chain_set_standing_waves(c, tones, 1, 1e-3);
  chain_accelerations(c);
  std::vector<int> bead(3, 0);  // a bead where sin(tone 2 pi x / n) is large
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < n; ++i)
      if (std::abs(std::sin(tones[k] * 2 * M_PI * i / n)) >
          std::abs(std::sin(tones[k] * 2 * M_PI * bead[k] / n)))
        bead[k] = i;
  auto sample = [&]() {
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.u);
    return std::vector<double>{h(0, bead[0]), h(1, bead[1]), h(2, bead[2])};
  };
  std::vector<double> prev = sample(), first(3, -1), last(3, -1);
  std::vector<int> crossings(3, 0);
  for (int s = 1; s <= 4000; ++s) {
    chain_advance(c, dt, 1);
    const auto now = sample();
    for (int k = 0; k < 3; ++k) {
      if ((prev[k] > 0) != (now[k] > 0)) {
        const double t = (s - 1 + prev[k] / (prev[k] - now[k])) * dt;
        if (first[k] < 0) first[k] = t;
        last[k] = t, ++crossings[k];
      }
    }
    prev = now;
  }
  for (int k = 0; k < 3; ++k) {
    const double w = 2 * std::sqrt(1.5) * std::abs(std::sin(M_PI * tones[k] / n));
    const double w_verlet = 2 / dt * std::asin(w * dt / 2);
    const double measured = M_PI * (crossings[k] - 1) / (last[k] - first[k]);
    EXPECT_NEAR(measured / w_verlet, 1.0, 1e-6) << "tone " << tones[k];
    EXPECT_GT(crossings[k], 10);
  }
}

// Verlet's energy error and its trajectory error against the exact solution both fall by
// 4 when dt halves (disordered chain, fixed walls, linearized forces).
TYPED_TEST(ChainTest, VerletEnergyAndTrajectoryErrorsAreSecondOrderAgainstTheExactSolution) {
  const double T = 40.0;
  double energy_err[2], traj_err[2];
  for (int k = 0; k < 2; ++k) {
    const double dt = 0.1 / (1 << k);
    ChainBatch<TypeParam> c(spec_of(48, ChainBoundary::Fixed, ChainForce::Linear, 0.2), {5});
    chain_set_impulse(c, 0, 0.01);
    chain_accelerations(c);
    const auto e0 = chain_totals(c).linear[0];
    double worst = 0;
    const long steps = std::lround(T / dt);
    for (long s = 0; s < steps; s += 10) {
      chain_advance(c, dt, 10);
      worst = std::max(worst, std::abs(chain_totals(c).linear[0] / e0 - 1));
    }
    energy_err[k] = worst;
    auto ex = exact_of(c, 0);
    Eigen::VectorXd u0 = Eigen::VectorXd::Zero(48), v0 = Eigen::VectorXd::Zero(48), u, v;
    v0(0) = 0.01;
    ex.set_initial(u0, v0);
    ex.state(c.time, u, v);
    traj_err[k] = (vec(row<TypeParam>(c.u, 0)) - u).norm() / u.norm();
  }
  EXPECT_NEAR(energy_err[0] / energy_err[1], 4.0, 0.4);
  EXPECT_NEAR(traj_err[0] / traj_err[1], 4.0, 0.4);
  EXPECT_LT(traj_err[1], 0.06);  // phase error of the fastest modes after t = 40
}

// The Hertz chain's own energy (exact Hertz potential) is also conserved to O(dt^2).
TYPED_TEST(ChainTest, HertzChainEnergyErrorIsSecondOrder) {
  double err[2];
  for (int k = 0; k < 2; ++k) {
    const double dt = 0.2 / (1 << k);
    ChainBatch<TypeParam> c(spec_of(40, ChainBoundary::Periodic, ChainForce::Hertz, 0.1), {1});
    chain_set_impulse(c, 3, 0.05);
    chain_accelerations(c);
    const auto e0 = chain_totals(c).hertz[0];
    double worst = 0;
    for (int s = 0; s < 30 * (1 << k); ++s) {
      chain_advance(c, dt, 5);
      worst = std::max(worst, std::abs(chain_totals(c).hertz[0] / e0 - 1));
    }
    err[k] = worst;
  }
  EXPECT_NEAR(err[0] / err[1], 4.0, 0.5);
}

// Ordered ring with an even bead count: the k = pi mode sits exactly at omega_max =
// 2 sqrt(3/2). Just below 2/omega_max Verlet stays bounded, just above it the divergence
// guard stops the run.
TYPED_TEST(ChainTest, VerletIsBoundedBelowTheStabilityEdgeAndStoppedAboveIt) {
  const double edge = 2.0 / (2.0 * std::sqrt(1.5));
  auto run = [](double dt) {
    ChainBatch<TypeParam> c(spec_of(32, ChainBoundary::Periodic, ChainForce::Linear, 0.0), {0});
    chain_set_impulse(c, 0, 0.01);
    chain_accelerations(c);
    const auto e0 = chain_totals(c).linear;
    const auto t = chain_advance_guarded(c, dt, 4000, e0);
    return t.linear[0] / e0[0];
  };
  double ratio = 0;
  EXPECT_NO_THROW(ratio = run(0.99 * edge));
  EXPECT_LT(ratio, 100.0);
  EXPECT_THROW(run(1.01 * edge), PhysicsError);
}

TYPED_TEST(ChainTest, OpeningContactStopsTheRun) {
  ChainBatch<TypeParam> c(spec_of(16, ChainBoundary::Fixed, ChainForce::Hertz, 0.0), {0});
  chain_set_impulse(c, 0, 2.0);  // far beyond the pre-compression: the contact behind opens
  chain_accelerations(c);
  EXPECT_THROW(chain_advance(c, 0.05, 200), PhysicsError);
}

// Realization r depends only on (seed, r): a batch of {0..5} and a batch of {4, 2} give
// bitwise the same rows, on this space and on the serial (one-thread) space.
TYPED_TEST(ChainTest, ResultsAreBitwiseIdenticalAcrossBatchSizesAndThreadCounts) {
  const auto spec = spec_of(100, ChainBoundary::Fixed, ChainForce::Hertz, 0.3, 11);
  ChainBatch<TypeParam> big(spec, ChainBatch<TypeParam>::first(6));
  ChainBatch<TypeParam> small(spec, {4, 2});
  auto go = [](auto& c) {
    chain_set_impulse(c, 0, 0.01);
    chain_accelerations(c);
    chain_advance(c, 0.1, 500);
  };
  go(big), go(small);
  EXPECT_EQ(row<TypeParam>(big.u, 4), row<TypeParam>(small.u, 0));
  EXPECT_EQ(row<TypeParam>(big.v, 2), row<TypeParam>(small.v, 1));
#ifdef KOKKOS_ENABLE_SERIAL
  // Device compilers may contract to FMA differently from the host: compare host spaces.
  if constexpr (Kokkos::SpaceAccessibility<Kokkos::HostSpace,
                                           typename TypeParam::memory_space>::accessible) {
    ChainBatch<Kokkos::Serial> serial(spec, {2});
    go(serial);
    EXPECT_EQ(row<TypeParam>(big.u, 2), row<Kokkos::Serial>(serial.u, 0));
    EXPECT_EQ(chain_totals(big).linear[2], chain_totals(serial).linear[0]);
  }
#endif
  EXPECT_NE(row<TypeParam>(big.u, 2), row<TypeParam>(big.u, 4));  // disorder differs
}

TEST(ChainDisorder, MassesHaveUnitMeanAndTheRequestedSpread) {
  ChainSpec s = spec_of(20000, ChainBoundary::Fixed, ChainForce::Hertz, 0.1, 3);
  const auto m = chain_masses(s, 9);
  double mean = 0, var = 0;
  for (double x : m) mean += x;
  mean /= m.size();
  for (double x : m) var += (x - mean) * (x - mean);
  EXPECT_NEAR(mean, 1.0, 1e-14);
  EXPECT_NEAR(std::sqrt(var / m.size()), 0.1, 0.003);  // 3 sigma of the sample sd
  EXPECT_DOUBLE_EQ(chain_pair_kappa(StiffnessRule::Radius, 1, 1), 1.0);
  EXPECT_DOUBLE_EQ(chain_pair_kappa(StiffnessRule::Mass, 1, 1), 1.0);
  EXPECT_NE(chain_masses(s, 9), chain_masses(s, 10));
}

TEST(ChainScene, TimeStepBeyondTheStabilityLimitIsRefusedNamingTheKeyAndFile) {
  const std::string text =
      "scene = \"chain_impulse\"\n[chain]\nbeads = 64\n[disorder]\nxi = [0.1]\n"
      "realizations = 4\n[time]\ndt = 0.9\nsample_every = 1.8\n";
  try {
    read_chain_scene(SceneFile::parse(text, "bad_chain.toml"));
    FAIL() << "dt = 0.9 > 2/omega_max was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("time.dt"), std::string::npos) << msg;
    EXPECT_NE(msg.find("bad_chain.toml"), std::string::npos) << msg;
    EXPECT_NE(msg.find("stability"), std::string::npos) << msg;
  }
}

// The late-time analysis stops before the front reflects from the far wall: in an ordered
// chain run well past the arrival, the reflected pulse comes back to the source bead, and
// the residual source energy must still be that of the window before the arrival (zero).
TEST(ChainScene, LateTimeAnalysisEndsBeforeTheFrontReflects) {
  const std::string text =
      "scene = \"chain_impulse\"\n[chain]\nbeads = 64\n[disorder]\nxi = [0.0]\n"
      "realizations = 2\n[impulse]\nv0 = 0.01\n[time]\ndt = 0.125\nt_max = 120\n"
      "sample_every = 1.0\n[analysis]\nnear_source_beads = 10\npower_law_beads = 40\n";
  RunOptions opts;
  opts.out_dir = granular::testing::temp_dir("chain_window");
  opts.progress = false, opts.charts = false;
  const SceneFile scene = SceneFile::parse(text, "window.toml");
  (void)scene.text("scene");
  run_chain_impulse(scene, opts);
  const H5Reader r(opts.out_dir + "/results.h5");
  const double t_front = r.attribute("/xi_0", "t_front_far_end");
  const long end = std::lround(r.attribute("/xi_0", "analysis_end_sample"));
  const auto t = r.reals("/xi_0/time");
  const auto e = r.reals("/xi_0/source_energy");
  const auto per_realization = r.reals("/xi_0/source_fraction_per_realization");
  const double e0 = r.attribute("/", "energy0");
  EXPECT_NEAR(t_front, 63 / std::sqrt(1.5), 1e-12);
  EXPECT_LE(t[end], 0.95 * t_front);
  EXPECT_GT(t[end + 1], 0.95 * t_front);
  // The reflection is really in the run: the source bead has energy again near t = 2 t_front.
  double back = 0;
  for (size_t s = 0; s < t.size(); ++s)
    if (t[s] > 1.9 * t_front) back = std::max(back, e[s] / e0);
  EXPECT_GT(back, 1e-2);
  // Within the window the ordered chain has carried all of it away.
  for (long s = end - end / 10; s <= end; ++s) EXPECT_LT(e[s] / e0, 1e-4) << t[s];
  // Unit masses: each realization's fraction is the ratio of the means.
  for (size_t s = 0; s < t.size(); ++s)
    EXPECT_NEAR(per_realization[s], e[s] / e0, 1e-12 * (1 + per_realization[s]));
  std::filesystem::remove_all(opts.out_dir);
}

namespace {
// The ensemble-mean bead energies (all samples) of a linearized chain_impulse run, and the
// worst energy drift, with the given [time] table.
struct ImpulseRun {
  std::vector<double> te, drift;
};
ImpulseRun linear_impulse(const std::string& time_table, const std::string& tag) {
  const std::string text =
      "scene = \"chain_impulse\"\n[chain]\nbeads = 48\nforce = \"linear\"\n"
      "[disorder]\nxi = [0.2]\nrealizations = 5\n[impulse]\nv0 = 0.01\n[time]\n" +
      time_table + "t_max = 30\nsample_every = 1.0\n[analysis]\nnear_source_beads = 10\n";
  RunOptions opts;
  opts.out_dir = granular::testing::temp_dir("chain_solver_" + tag);
  opts.progress = false, opts.charts = false;
  const SceneFile scene = SceneFile::parse(text, tag + ".toml");
  (void)scene.text("scene");
  run_chain_impulse(scene, opts);
  const H5Reader r(opts.out_dir + "/results.h5");
  ImpulseRun out{r.reals("/xi_0/te_mean"), r.reals("/xi_0/energy_drift")};
  std::filesystem::remove_all(opts.out_dir);
  return out;
}
}  // namespace

// The exact solver of chain_impulse (eigenmodes of each realization, 5 of them: a partial
// batch) against Verlet on the same linearized chains: Verlet converges to it at second
// order in the time step, and the exact solution conserves energy to round-off.
TEST(ChainScene, ExactSolverIsTheLimitOfVerletAndConservesEnergy) {
  const ImpulseRun exact = linear_impulse("solver = \"exact\"\n", "exact");
  const ImpulseRun coarse = linear_impulse("dt = 0.02\n", "verlet_coarse");
  const ImpulseRun fine = linear_impulse("dt = 0.01\n", "verlet_fine");
  ASSERT_EQ(exact.te.size(), 31u * 48u);
  ASSERT_EQ(fine.te.size(), exact.te.size());
  double scale = 0, err_coarse = 0, err_fine = 0;
  for (size_t i = 0; i < exact.te.size(); ++i) {
    scale = std::max(scale, std::abs(exact.te[i]));
    err_coarse = std::max(err_coarse, std::abs(coarse.te[i] - exact.te[i]));
    err_fine = std::max(err_fine, std::abs(fine.te[i] - exact.te[i]));
  }
  EXPECT_LT(err_fine / scale, 2e-3);
  EXPECT_NEAR(err_coarse / err_fine, 4.0, 0.6);  // second order
  for (double d : exact.drift) EXPECT_LT(d, 1e-12);
}

// The stability limit 2/omega_max from the Sturm bisection against the closed form of the
// ordered chain with walls and against the eigensolver for a disordered chain; a time step
// at the limit is refused before any step.
TEST(ChainStability, SturmLimitMatchesTheEigenvaluesAndRefusesLargerSteps) {
  using Host = Kokkos::DefaultHostExecutionSpace;
  ChainBatch<Host> ordered(spec_of(40, ChainBoundary::Fixed, ChainForce::Linear, 0.0), {0});
  const double w_max = 2 * std::sqrt(1.5) * std::sin(M_PI * 40 / (2.0 * 41));
  EXPECT_NEAR(chain_stability_limits(ordered)[0], 2 / w_max, 1e-12);
  ChainBatch<Host> c(spec_of(60, ChainBoundary::Fixed, ChainForce::Hertz, 0.3), {0, 1, 2});
  const auto limits = chain_stability_limits(c);
  for (int r = 0; r < 3; ++r)
    EXPECT_NEAR(limits[r], 2 / exact_of(c, r).omega().maxCoeff(), 1e-10 * limits[r]);
  const double lowest = *std::min_element(limits.begin(), limits.end());
  EXPECT_NO_THROW(chain_check_time_step(c, 0.999 * lowest));
  EXPECT_THROW(chain_check_time_step(c, lowest), PhysicsError);
}
