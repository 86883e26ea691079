// Physical-safety guards: a time step beyond t_c/10 of the stiffest, lightest pair is
// refused with the limit in the message; a run driven into huge overlaps is stopped.
// And output files: an unfinished HDF5 file never appears under its final name. A phase
// projected past the run's wall-time budget stops with the estimate.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "core/io/output.hpp"
#include "core/run/progress.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::shipped_scene;
using granular::testing::temp_dir;
using Exec = Kokkos::DefaultExecutionSpace;

namespace {
HostParticles small_gas(PeriodicBox& box, double speed) {
  GasSpec g;
  g.count = 300, g.diameter_min = 1, g.diameter_max = 3, g.density = 2000, g.phi = 0.3;
  g.speed = speed;
  return random_gas(g, box);
}
}  // namespace

TEST(SafetyGuards, TimeStepAboveTenthOfShortestContactIsRefusedWithTheLimit) {
  PeriodicBox box;
  const HostParticles h = small_gas(box, 0.0);
  const auto model = frictionless_linear(1e5, 1000);
  // Lightest pair: two smallest spheres in the gas (d close to 1).
  double m0 = 1e300, m1 = 1e300;
  for (int i = 0; i < h.size(); ++i) {
    const double m = 2000 * 4.0 / 3 * M_PI * std::pow(h.radius[i], 3);
    if (m < m0)
      m1 = m0, m0 = m;
    else if (m < m1)
      m1 = m;
  }
  const double limit = 0.1 * model.normal.contact_duration(m0 * m1 / (m0 + m1));
  DemParams prm;
  prm.skin = 0.2;
  prm.dt = 0.99 * limit;
  EXPECT_NO_THROW(
      (DemSystem<Exec, FrictionlessLinear>(Particles<Exec>::from_host(h), box, model, prm)));
  prm.dt = 1.01 * limit;
  try {
    DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(h), box, model, prm);
    FAIL() << "time step above t_c/10 accepted";
  } catch (const PhysicsError& e) {
    EXPECT_NE(std::string(e.what()).find("set dt <="), std::string::npos) << e.what();
    // A linear spring's stiffness does not depend on the overlap: no overlap limit named.
    EXPECT_EQ(std::string(e.what()).find("max_overlap"), std::string::npos) << e.what();
  }
}

// A Hertz contact stiffens with the overlap, and the guard takes it at the overlap limit: the
// refusal names that limit, so a user whose overlaps stay far below it knows a lower
// run.max_overlap also relaxes the bound (docs/guide_waves.md, the Mindlin mixtures).
TEST(SafetyGuards, OverlapDependentStiffnessNamesTheOverlapLimitItIsTakenAt) {
  PeriodicBox box;
  const HostParticles h = small_gas(box, 0.0);
  const ContactModel<HertzNormal> model{
      {PairTable<HertzNormal::Params>::uniform({1e5, 0, true})}, {}, {}};
  DemParams prm;
  prm.skin = 0.2;
  prm.dt = 10.0;  // far above any contact duration here
  prm.max_overlap = 0.25;
  try {
    DemSystem<Exec, ContactModel<HertzNormal>> sys(Particles<Exec>::from_host(h), box, model, prm);
    FAIL() << "time step above t_c/10 accepted";
  } catch (const PhysicsError& e) {
    EXPECT_NE(std::string(e.what()).find("overlap limit max_overlap = 0.25"), std::string::npos)
        << e.what();
  }
}

TEST(SafetyGuards, ViolentCollisionsStopTheRunWithRunawayMessage) {
  PeriodicBox box;
  const HostParticles h = small_gas(box, 2.0);  // 2 mm/us: overlaps far beyond binary contacts
  const auto model = frictionless_linear(1e5, 0);
  DemParams prm;
  prm.skin = 0.2, prm.dt = 0.004;
  DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(h), box, model, prm);
  bool stopped = false;
  for (int k = 0; k < 200 && !stopped; ++k) {
    sys.step(10);
    try {
      sys.check_health(sys.measure());
    } catch (const PhysicsError& e) {
      stopped = true;
      EXPECT_NE(std::string(e.what()).find("runaway"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(stopped);
}

TEST(SafetyGuards, GentleGasPassesTheHealthCheck) {
  PeriodicBox box;
  const HostParticles h = small_gas(box, 0.001);
  DemParams prm;
  prm.skin = 0.2, prm.dt = 0.004;
  DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(h), box,
                                          frictionless_linear(1e5, 1000), prm);
  sys.step(500);
  EXPECT_NO_THROW(sys.check_health(sys.measure()));
}

TEST(AtomicOutput, UnfinishedFileNeverAppearsUnderItsFinalName) {
  const auto dir = granular::testing::unique_temp_path("granular_atomic_test");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "results.h5").string();
  {
    H5Writer w(path);
    w.write("/a/b", std::vector<double>{1, 2, 3});
    EXPECT_FALSE(std::filesystem::exists(path));  // still under the partial name
  }  // destroyed without commit, as when a run is interrupted by an exception
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(partial_name(path)));
  {
    H5Writer w(path);
    w.write("/a/b", std::vector<double>{1, 2, 3});
    w.commit();
  }
  ASSERT_TRUE(std::filesystem::exists(path));
  EXPECT_EQ(H5Reader(path).reals("/a/b"), (std::vector<double>{1, 2, 3}));
  std::filesystem::remove_all(dir);
}

// Rolling and torsion springs and dashpots are guarded like the normal and tangential ones:
// a stiffness or damping the explicit step cannot follow is refused before the first step
// (they used to be left out of the guard, which saw only the normal contact here).
TEST(SafetyGuards, StiffRollingOrTorsionSpringAndFastRollingDashpotAreRefused) {
  using Rolling = ContactModel<LinearNormal, NoTangential, RollingTorsion>;
  PeriodicBox box;
  const HostParticles h = small_gas(box, 0.0);
  DemParams prm;
  prm.skin = 0.2;
  prm.dt = 0.004;  // t_c/57 of the normal contact (kn = 1e5) for the smallest pair
  auto build = [&](const RollingTorsion::Params& q) {
    const Rolling model{LinearNormal::uniform(1e5, 0), {}, RollingTorsion::uniform(q)};
    DemSystem<Exec, Rolling>(Particles<Exec>::from_host(h), box, model, prm);
  };
  EXPECT_NO_THROW(build({1e4, 10, 0.1, 1e4, 10, 0.1}));
  for (const RollingTorsion::Params& q : {RollingTorsion::Params{1e9, 0, 0.1, 0, 0, 0.1},
                                          RollingTorsion::Params{0, 0, 0.1, 1e9, 0, 0.1},
                                          RollingTorsion::Params{0, 1e8, 0.1, 0, 0, 0.1}}) {
    try {
      build(q);
      ADD_FAILURE() << "kr " << q.kr << ", ko " << q.ko << ", gamma_r " << q.gr << " accepted";
    } catch (const PhysicsError& e) {
      EXPECT_NE(std::string(e.what()).find("dt"), std::string::npos) << e.what();
    }
  }
}

TEST(WallTimeBudget, ProjectionIsJudgedOnlyOnceTheRateIsMeasured) {
  const double hour = 3600;
  EXPECT_FALSE(Progress::over_budget(10, 1, 1000, hour));    // too early: 30 s not yet spent
  EXPECT_TRUE(Progress::over_budget(40, 1, 1000, hour));     // 40 000 s projected
  EXPECT_FALSE(Progress::over_budget(40, 500, 1000, hour));  // 80 s projected
  EXPECT_FALSE(Progress::over_budget(1e6, 1, 1000, 0));      // no budget
  EXPECT_FALSE(Progress::over_budget(40, 0, 1000, hour));    // no step yet: no rate
  // A short budget is judged after a tenth of it.
  EXPECT_TRUE(Progress::over_budget(0.2, 1, 1000, 1.0));
  EXPECT_FALSE(Progress::over_budget(0.05, 1, 1000, 1.0));
}

TEST(WallTimeBudget, PhaseProjectedPastTheBudgetStopsWithTheEstimateEvenWithoutProgressLines) {
  const double kept = Progress::budget_hours();
  Progress::set_budget_hours(1e-6);  // 3.6 ms, judged after 0.36 ms
  {
    Progress p("long phase", 1000000, false);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    try {
      p.update(1);
      ADD_FAILURE() << "a phase of about 1.4 h passed a budget of 3.6 ms";
    } catch (const PhysicsError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("'long phase'"), std::string::npos) << what;
      EXPECT_NE(what.find("--max-hours"), std::string::npos) << what;
    }
  }
  Progress::set_budget_hours(0);  // none: the same phase goes on
  {
    Progress p("long phase", 1000000, false);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    EXPECT_NO_THROW(p.update(1));
  }
  Progress::set_budget_hours(kept);
}
