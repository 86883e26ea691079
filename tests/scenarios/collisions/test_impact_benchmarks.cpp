// Defects the published impact benchmarks (Chung & Ooi 2011) exposed in the contact layer,
// each guarded here: a tangential spring along the normal (head-on frictional impacts), the
// slip reset of the restitution-damped Mindlin law (friction along the slip), NaN results
// that read as perfect, and the time-step guard over pairs that cannot touch.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <tuple>

#include "core/dem/restitution.hpp"
#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "core/run/finite.hpp"
#include "granular_config.hpp"
#include "kernels/contact/contact_model.hpp"
#include "scenarios/collisions/impact.hpp"
#include "scenarios/collisions/impact_closed_forms.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using HertzMindlin = ContactModel<HertzRestitutionNormal, CoulombTangential>;

// Hertz with restitution damping and the restitution-damped Mindlin spring for one
// material pair (species 0 with itself, and with the wall slot 1), SI-like units of the
// engine: mm, us, ug (E in N/mm^2 = MPa).
HertzMindlin hertz_mindlin(double E, double nu, double e, double mu, bool wall) {
  const double G = E / (2 * (1 + nu));
  const double estar = wall ? E / (1 - nu * nu) : effective_young(E, nu, E, nu);
  const double gstar = wall ? G / (2 - nu) : effective_shear(G, nu, G, nu);
  const double alpha = e < 1 ? hertz_alpha_exact(e) : 0.0;
  const double gt = e < 1 ? mindlin_gt_common(e) : 0.0;
  return {HertzRestitutionNormal::uniform(4.0 / 3.0 * estar, alpha),
          CoulombTangential::uniform(8 * gstar, gt, mu, mu, CoulombTangential::MindlinRestitution),
          {}};
}

double sphere_mass(double a, double rho) { return rho * 4.0 / 3.0 * M_PI * a * a * a; }

// 27 unit spheres on a 3 x 3 x 3 lattice 0.1 apart, in a periodic box (a packing whose
// health check has something to measure).
HostParticles spaced_lattice(PeriodicBox& box) {
  HostParticles h;
  h.resize(27);
  for (int i = 0; i < 27; ++i) {
    h.x[i] = 1.0 + 2.1 * (i % 3), h.y[i] = 1.0 + 2.1 * (i / 3 % 3), h.z[i] = 1.0 + 2.1 * (i / 9);
    h.radius[i] = 1.0, h.density[i] = 1.0;
  }
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = 6.3;
  return h;
}

// Steps of a recorded impact, in the contact's own frame: sliding steps (|f_t| at the
// Coulomb limit); steps with |f_t| above the limit mu |f_n| (beyond round-off); and sliding
// steps of the loading phase where friction pushes along the slip (f_t . v_c > 0). While the
// normal force grows the spring at the limit lengthens (|xi| = mu |f_n| / k_t grows, also for
// Mindlin's k_t ~ sqrt(delta)), so the contact point's velocity, the slider's plus the
// spring's, opposes the force. While it falls, a spring at the limit recovers, and the
// contact point may move along the force without any slider moving so: that is the
// tangential restitution of a compliant contact, not friction pushing. Slips below 1 % of the
// impact speed are left out: where the slip reverses, the velocity the force was computed
// with (half a step earlier) may have the other sign.
struct FrictionCount {
  int sliding = 0, along = 0, over = 0;
};
// kh > 0: the limit takes the elastic normal force kh delta^{3/2} (Hertz), not the total.
FrictionCount count_friction(const ImpactResult& r, double mu, double speed, double kh = 0) {
  FrictionCount c;
  for (size_t k = 1; k < r.t.size(); ++k) {
    if (r.overlap[k] <= 0) continue;
    const double ft = r.contact_tangential_force[k];
    const double fn =
        kh > 0 ? kh * std::pow(r.overlap[k], 1.5) : std::fabs(r.contact_normal_force[k]);
    if (ft > mu * fn * (1 + 1e-9) + 1e-300) ++c.over;
    if (!(ft >= mu * fn * (1 - 1e-9) && fn > 0)) continue;
    ++c.sliding;
    const bool loading = r.contact_normal_force[k] > r.contact_normal_force[k - 1];
    if (loading && r.friction_power[k] > 0 && r.contact_slip_speed[k] > 1e-2 * speed) ++c.along;
  }
  return c;
}

}  // namespace

// ---- the spring's rotation into the tangent plane ------------------------------------

// n as the kernels form it: r times 1/|r|, unit only to round-off.
static void kernel_normal(const double r[3], double n[3]) {
  const double inv = 1.0 / std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  for (int d = 0; d < 3; ++d) n[d] = r[d] * inv;
}

TEST(SpringRotation, SpringAlongNormalIsReleasedNotNaN) {
  // Many directions: along some of them |n| > 1 by round-off, so x = (s.n)^2/|s|^2 > 1.
  int released = 0;
  for (int k = 0; k < 2000; ++k) {
    const double r[3] = {std::sin(0.37 * k) * 1.3, std::cos(0.11 * k) * 0.7, 0.2 + 0.001 * k};
    double n[3];
    kernel_normal(r, n);
    for (double len : {1e-300, 1e-12, 1.0, 1e200}) {
      double s[3] = {n[0] * len, n[1] * len, n[2] * len};
      rotate_into_plane(s, n);
      for (double c : s) ASSERT_TRUE(std::isfinite(c)) << k << " " << len;
      EXPECT_EQ(dot3(s, s), 0.0) << "a spring along n has no direction in the plane";
      ++released;
    }
  }
  EXPECT_EQ(released, 8000);
}

TEST(SpringRotation, SpringNearlyAlongNormalStaysFiniteAndInPlane) {
  const double r[3] = {0.3, -1.1, 0.8};
  double n[3], t[3] = {1.1, 0.3, 0.0};  // t is normal to r: r.t = 0.33 - 0.33 = 0
  kernel_normal(r, n);
  const double tl = norm3(t);
  for (double off : {1e-12, 1e-8, 1e-4, 1e-2, 0.5}) {
    double s[3];
    for (int d = 0; d < 3; ++d) s[d] = n[d] + off * t[d] / tl;
    const double len = norm3(s);
    rotate_into_plane(s, n);
    for (double c : s) ASSERT_TRUE(std::isfinite(c)) << off;
    const double out = norm3(s);
    EXPECT_LE(std::fabs(dot3(s, n)), 1e-12 * len) << off;
    if (off < 1e-3) {
      EXPECT_EQ(out, 0.0) << off;  // within 1e-3 rad of n: released
    } else {
      EXPECT_NEAR(out / len, 1.0, 1e-12) << "rotation keeps the length, off " << off;
    }
  }
  double zero[3] = {0, 0, 0};
  rotate_into_plane(zero, n);
  EXPECT_EQ(zero[0], 0.0);
  EXPECT_EQ(zero[1], 0.0);
  EXPECT_EQ(zero[2], 0.0);
}

TEST(SpringRotation, RollingAndTorsionSurviveSpringsAlongNormal) {
  const RollingTorsion rt = RollingTorsion::uniform({2.0, 0.1, 0.3, 1.5, 0.1, 0.2});
  PairState s{};
  const double r[3] = {0.4, 0.9, -1.3};
  kernel_normal(r, s.n);
  s.delta = 1e-3, s.ai = s.aj = 1.0, s.mstar = 1.0;
  s.wrel[0] = 0.1, s.wrel[1] = -0.2, s.wrel[2] = 0.05;
  for (double len : {0.0, 1e-12, 1.0}) {
    double h[6];
    for (int d = 0; d < 3; ++d) h[d] = s.n[d] * len, h[3 + d] = s.n[d] * len;
    double q[3] = {0, 0, 0};
    rt.torque(s, 1.0, 1e-3, h, q);
    for (int d = 0; d < 3; ++d) {
      ASSERT_TRUE(std::isfinite(q[d])) << len;
      ASSERT_TRUE(std::isfinite(h[d]) && std::isfinite(h[3 + d])) << len;
    }
    EXPECT_LE(std::fabs(dot3(h, s.n)), 1e-12) << "rolling spring in the plane";
  }
}

// ---- impacts -------------------------------------------------------------------------

template <class T>
class ImpactBenchmark : public ::testing::Test {};
TYPED_TEST_SUITE(ImpactBenchmark, granular::testing::ExecSpaces);

// Chung & Ooi test 1: two equal glass spheres (E = 48 GPa, nu = 0.2, rho = 2800 kg/m^3,
// R = 10 mm) meeting head-on at +-10 m/s with mu = 0.35, elastic. The tangential spring
// only ever holds round-off along n; it used to turn into NaN about 18 steps into the contact.
TYPED_TEST(ImpactBenchmark, HeadOnFrictionalImpactOfEqualSpheresIsElasticHertz) {
  for (const auto& [E, nu, rho] : {std::tuple{48e3, 0.2, 2800.0}, std::tuple{20e3, 0.25, 2500.0}}) {
    const double a = 10.0, v = 0.02;  // mm; relative speed 20 m/s = 0.02 mm/us
    const HertzMindlin model = hertz_mindlin(E, nu, 1.0, 0.35, false);
    // Densities in the engine's units: kg/m^3 = ug/mm^3.
    const double mstar = 0.5 * sphere_mass(a, rho);
    const HertzClosedForm cf = hertz_closed_form(effective_young(E, nu, E, nu), 0.5 * a, mstar, v);
    ImpactSetup s;
    s.wall = false;
    s.radius1 = s.radius2 = a, s.density1 = s.density2 = rho, s.speed = v;
    s.dt = cf.duration / 4000;
    const auto r = impact<TypeParam>(model, s);
    ASSERT_TRUE(r.separated);
    EXPECT_NEAR(r.duration / cf.duration, 1.0, 1e-4) << E;
    EXPECT_NEAR(r.max_overlap / cf.overlap, 1.0, 1e-4) << E;
    EXPECT_NEAR(r.max_normal_force / cf.force, 1.0, 1e-4) << E;
    EXPECT_NEAR(r.restitution_normal, 1.0, 1e-6) << E;
    EXPECT_EQ(r.vc_in, 0.0);
    EXPECT_TRUE(std::isfinite(r.restitution_tangential));
    EXPECT_LT(std::fabs(r.vt_out), 1e-12 * v) << "no tangential motion from round-off";
  }
}

// Tests 6 and 8 of the benchmark: oblique impacts of a restitution-damped (e = 0.5) Mindlin
// contact, on a wall and on an equal sphere. While the contact slides under a growing normal
// force, friction must oppose the slip; it may never exceed the Coulomb limit mu |f_n|. In
// gross sliding the tangential impulse is mu J_n exactly when the limit takes the elastic
// normal force (the dashpot's impulse over a whole impact is zero), and mu (J_n + 2 J_tensile)
// with the total force, the default (docs/contact_laws.md).
TYPED_TEST(ImpactBenchmark, FrictionNeverPushesAlongTheSlipNorExceedsCoulomb) {
  const double E = 70e3, nu = 0.33, rho = 2700, a = 100.0, mu = 0.4, e = 0.5;  // Al alloy
  for (bool wall : {true, false}) {
    for (bool elastic_limit : {false, true}) {
      HertzMindlin model = hertz_mindlin(E, nu, e, mu, wall);
      model.coulomb_elastic_normal = elastic_limit;
      for (double angle_deg : {5.0, 20.0, 45.0, 70.0, 85.0}) {
        const std::string what = std::string(wall ? "wall " : "pair ") +
                                 (elastic_limit ? "elastic limit " : "total limit ") +
                                 std::to_string(angle_deg);
        ImpactSetup s;
        s.wall = wall, s.wall_material = 0;
        s.radius1 = s.radius2 = a, s.density1 = s.density2 = rho;
        s.speed = 3.9e-3, s.angle = angle_deg * M_PI / 180;
        const double m = sphere_mass(a, rho), mstar = wall ? m : 0.5 * m;
        const double estar = wall ? E / (1 - nu * nu) : effective_young(E, nu, E, nu);
        const double vn = s.speed * std::cos(s.angle);
        s.dt = hertz_closed_form(estar, wall ? a : 0.5 * a, mstar, vn).duration / 400;
        s.record = true;
        const auto r = impact<TypeParam>(model, s);
        ASSERT_TRUE(r.separated) << what;
        const double kh = 4.0 / 3.0 * estar * std::sqrt(wall ? a : 0.5 * a);
        const FrictionCount n = count_friction(r, mu, s.speed, elastic_limit ? kh : 0.0);
        EXPECT_EQ(n.over, 0) << what;
        EXPECT_EQ(n.along, 0) << what << " of " << n.sliding << " sliding steps";
        const GrossSliding g = gross_sliding(m, a, mstar, r.vn_in, r.vt_in, r.spin_in, r.vc_in, mu,
                                             r.restitution_normal);
        // Impulses in the contact frame (the pair's normal turns as the spheres pass).
        double jn = 0, jt = 0;
        for (size_t k = 0; k < r.t.size(); ++k)
          jn += r.contact_normal_force[k], jt += r.contact_tangential_force[k];
        const double ratio = jt / jn;
        if (!g.slides) {
          EXPECT_LT(ratio, mu * 1.1) << what;
          continue;
        }
        ::testing::Test::RecordProperty(what, std::to_string(ratio / mu));
        if (elastic_limit)
          EXPECT_NEAR(ratio / mu, 1.0, 2e-3) << what;
        else
          EXPECT_TRUE(ratio > mu * 1.01 && ratio < mu * 1.1) << what << ": " << ratio / mu;
      }
    }
  }
}

// The same check for the laws whose slip reset keeps the dashpot's share in the spring
// (g/k constant over the contact: Luding's reset, as LAMMPS writes it): the linear spring
// with a constant dashpot, and Mindlin's sqrt(R delta) spring with a dashpot that scales
// alike, on a damped Hertz contact.
TYPED_TEST(ImpactBenchmark, ConstantRatioLawsOpposeTheSlipWithTangentialDamping) {
  auto check = [](const auto& model, double mu, double speed, double dt, const char* law) {
    for (double angle_deg : {10.0, 30.0, 60.0, 80.0}) {
      ImpactSetup s;
      s.wall = false, s.radius1 = s.radius2 = 1.0, s.density1 = s.density2 = 1.0;
      s.speed = speed, s.angle = angle_deg * M_PI / 180, s.dt = dt, s.record = true;
      const auto r = impact<TypeParam>(model, s);
      ASSERT_TRUE(r.separated) << law;
      const FrictionCount n = count_friction(r, mu, s.speed);
      EXPECT_EQ(n.over, 0) << law << " " << angle_deg;
      EXPECT_EQ(n.along, 0) << law << " " << angle_deg;
      EXPECT_GT(n.sliding, 0) << law << " " << angle_deg;
    }
  };
  const ContactModel<LinearNormal, CoulombTangential> linear{
      LinearNormal::uniform(1e3, 5.0), CoulombTangential::uniform(800.0, 4.0, 0.3, 0.3), {}};
  check(linear, 0.3, 0.05, 1e-3, "linear");
  const double E = 1e4, nu = 0.3, G = E / (2 * (1 + nu));
  const ContactModel<HertzNormal, CoulombTangential> mindlin{
      {PairTable<HertzNormal::Params>::uniform(HertzNormal::modulus_form(E, nu, E, nu, 2.0))},
      CoulombTangential::uniform(8 * G / (2 * (2 - nu)), 1.0, 0.4, 0.4,
                                 CoulombTangential::MindlinReducedRadius),
      {}};
  check(mindlin, 0.4, 0.05, 2e-3, "mindlin sqrt(R delta)");
}

// A NaN in the state stops the impact with the quantity and the step named, instead of
// ending it as "separated" with a NaN restitution.
TYPED_TEST(ImpactBenchmark, NaNInStateStopsTheImpactNamingQuantityAndStep) {
  const HertzMindlin model = hertz_mindlin(70e3, 0.3, 0.8, 0.3, true);
  ImpactSetup s;
  s.radius1 = 1.0, s.density1 = 2.7, s.wall_material = 0, s.speed = 1e-3, s.dt = 1e-3;
  s.spin[1] = std::nan("");
  try {
    impact<TypeParam>(model, s);
    FAIL() << "a NaN spin must stop the impact";
  } catch (const PhysicsError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("non-finite angular velocity of sphere 1"), std::string::npos) << what;
    EXPECT_NE(what.find("at step 1 "), std::string::npos) << what;
  }
}

// A NaN planted in one particle of a packing stops the next health check naming the
// particle: the measurements alone missed it (a NaN distance reads as "apart", so the
// particle dropped out of every contact, maximum and sum).
TYPED_TEST(ImpactBenchmark, NaNPlantedInAPackingStopsTheHealthCheckNamingTheParticle) {
  using Exec = TypeParam;
  PeriodicBox box;
  const HostParticles h = spaced_lattice(box);
  DemParams prm;
  prm.dt = 1e-3, prm.skin = 0.3, prm.sort = false;
  DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(h), box,
                                          frictionless_linear(100.0, 0.0), prm);
  sys.step(5);
  sys.check_health(sys.measure());  // a healthy state passes
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().v);
  v(13, 1) = std::nan("");
  Kokkos::deep_copy(sys.particles().v, v);
  sys.step(1);
  try {
    sys.check_health(sys.measure());
    FAIL() << "a NaN velocity passed the health check";
  } catch (const PhysicsError& e) {
    EXPECT_NE(std::string(e.what()).find("of particle 13 "), std::string::npos) << e.what();
  }
}

// The step must resolve every spring and dashpot the run depends on, not only the normal
// spring: a stiff tangential spring, a strong contact dashpot, background or rotational
// damping too strong for the lightest particle each stop the run before it starts, naming
// what to change (they used to run and report K* = G* = 0 or null ratios).
TYPED_TEST(ImpactBenchmark, StepTooLongForTangentialSpringOrAnyDashpotIsRefused) {
  using Exec = TypeParam;
  PeriodicBox box;
  const HostParticles h = spaced_lattice(box);
  using Model = ContactModel<LinearNormal, CoulombTangential>;
  auto make = [&](double kt, double gt, double background, double rotational) {
    DemParams prm;
    prm.dt = 1e-3, prm.skin = 0.3, prm.dt_key = "run.dt";
    prm.damping.translational = background, prm.damping.rotational = rotational;
    const Model model{
        LinearNormal::uniform(100.0, 0.1), CoulombTangential::uniform(kt, gt, 0.5, 0.5), {}};
    DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
  };
  make(80.0, 0.1, 0.1, 0.01);  // a sound setting passes
  auto refused = [&](double kt, double gt, double background, double rotational,
                     const std::string& names) {
    try {
      make(kt, gt, background, rotational);
      ADD_FAILURE() << names << ": accepted";
    } catch (const PhysicsError& e) {
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("run.dt"), std::string::npos) << e.what();
    }
  };
  refused(1e12, 0.1, 0.1, 0.01, "set run.dt <=");  // the tangential spring's period
  refused(80.0, 2e8, 0.1, 0.01, "gamma_t");
  refused(80.0, 0.1, 1e9, 0.01, "damping.background");
  refused(80.0, 0.1, 0.1, 1e9, "damping.rotational");
}

// ---- results -------------------------------------------------------------------------

TEST(FiniteResults, MaxOverCasesKeepsNaN) {
  EXPECT_TRUE(std::isnan(max_keep_nan(0.0, std::nan(""))));
  EXPECT_TRUE(std::isnan(max_keep_nan(std::nan(""), 1.0)));
  EXPECT_EQ(max_keep_nan(0.5, 0.25), 0.5);
  // What it replaces: std::max drops a NaN in second place.
  EXPECT_EQ(std::max(0.0, std::nan("")), 0.0);
}

TEST(FiniteResults, SummaryWithNaNIsRefusedAndNotWritten) {
  const std::string dir = granular::testing::temp_dir("nan_summary");
  std::filesystem::create_directories(dir);
  Json summary = Json::object();
  summary["fine"] = 1.0;
  summary["undefined_on_purpose"] = Json();
  Json cases = Json::array();
  Json c = Json::object();
  c["restitution"] = std::nan("");
  cases.push(c);
  summary["cases"] = cases;
  summary["inf"] = kInf;
  try {
    write_summary(dir + "/summary.json", summary);
    FAIL() << "a NaN result must not be written";
  } catch (const PhysicsError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cases[0].restitution"), std::string::npos) << what;
    EXPECT_NE(what.find("inf"), std::string::npos) << what;
    EXPECT_EQ(what.find("undefined_on_purpose"), std::string::npos) << what;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/summary.json"));
  // Table cells may be undefined (NaN) where a column does not apply, when the caller says so.
  Json t = Json::object();
  Json table = Json::array();
  table.push(Json(std::vector<double>{1.0, std::nan("")}));
  t["table"] = table;
  write_summary(dir + "/summary.json", t, {"table"});
  EXPECT_TRUE(std::filesystem::exists(dir + "/summary.json"));
}

// ---- the time-step guard ---------------------------------------------------------------

// A light glass sphere on a single, far stiffer target sphere: the target's like pair
// cannot occur, so only the glass-target contact is guarded. The refusal of a too-large
// step names the key the caller gave.
TYPED_TEST(ImpactBenchmark, TimeStepGuardConsidersOnlyPairsThatCanTouch) {
  HertzMindlin model = hertz_mindlin(63e3, 0.23, 0.9, 0.3, false);
  auto& hn = model.normal.table.p;
  hn[1][1].K = 1e6 * hn[0][0].K;               // a very stiff species 1 ...
  hn[0][1].K = hn[1][0].K = 2.0 * hn[0][0].K;  // ... whose contact with glass is moderate
  ImpactSetup s;
  s.wall = false, s.radius1 = 1.0, s.radius2 = 5.0, s.density1 = 2.5, s.density2 = 8.0;
  s.species1 = 0, s.species2 = 1, s.speed = 1e-3;
  const double mstar = sphere_mass(1.0, 2.5) * sphere_mass(5.0, 8.0) /
                       (sphere_mass(1.0, 2.5) + sphere_mass(5.0, 8.0));
  const double estar = 0.75 * hn[0][1].K;
  s.dt = hertz_closed_form(estar, 5.0 / 6.0, mstar, s.speed).duration / 400;
  const auto r = impact<TypeParam>(model, s);  // refused before the fix (the 1-1 pair)
  EXPECT_TRUE(r.separated);
  s.dt *= 1e3;
  s.dt_hint = "raise impact.steps_per_contact";
  try {
    impact<TypeParam>(model, s);
    FAIL() << "a step beyond the stiffest pair's limit must be refused";
  } catch (const PhysicsError& e) {
    EXPECT_NE(std::string(e.what()).find("raise impact.steps_per_contact"), std::string::npos)
        << e.what();
  }
}

// ---- the shipped benchmark scene -------------------------------------------------------

// All eight tests of the shipped scene against their closed forms: elastic Hertz for the
// normal impacts (to 1e-4), the input restitution, and rigid-body gross sliding wherever the
// contact slides throughout (impulse ratio, spin change, tangential restitution). Every
// result finite, every test present.
TEST(ImpactBenchmarkScene, AllEightTestsMatchTheirClosedForms) {
  RunOptions opts;
  opts.out_dir = granular::testing::temp_dir("impact_benchmarks");
  opts.progress = false, opts.charts = false;
  const SceneFile scene = SceneFile::load(std::string(GRANULAR_SOURCE_DIR) +
                                          "/scenarios/collisions/impact_benchmarks.toml");
  ASSERT_EQ(scene.text("scene"), "impact_benchmarks");  // the CLI reads this key
  run_impact_benchmarks(scene, opts);
  const H5Reader r(opts.out_dir + "/results.h5");
  bool seen[9] = {};
  int sliding = 0;
  for (const std::string& name : scene.tables("cases")) {
    const std::string g = "/cases/" + name;
    const int test = static_cast<int>(r.attribute(g, "test"));
    seen[test] = true;
    const auto e_in = r.reals(g + "/restitution_input");
    const auto en = r.reals(g + "/restitution_normal");
    for (size_t k = 0; k < en.size(); ++k) {
      ASSERT_TRUE(std::isfinite(en[k])) << name;
      // 400 steps per contact: the integrator's error, 1.6e-3 of e at e = 0.2.
      EXPECT_NEAR(en[k] / e_in[k], 1.0, 2e-3) << name << " " << k;
    }
    if (test <= 2) {
      const auto t = r.reals(g + "/duration"), tc = r.reals(g + "/hertz_duration");
      const auto d = r.reals(g + "/max_overlap"), dc = r.reals(g + "/hertz_overlap");
      const auto f = r.reals(g + "/max_normal_force"), fc = r.reals(g + "/hertz_force");
      EXPECT_NEAR(t[0] / tc[0], 1.0, 1e-4) << name;
      EXPECT_NEAR(d[0] / dc[0], 1.0, 1e-4) << name;
      EXPECT_NEAR(f[0] / fc[0], 1.0, 1e-4) << name;
    }
    const auto slides = r.reals(g + "/gross_sliding");
    const auto ratio = r.reals(g + "/impulse_ratio");
    const auto ratio_cf = r.reals(g + "/closed_form_impulse_ratio");
    const auto spin = r.reals(g + "/spin_out"), spin_in = r.reals(g + "/spin_in");
    const auto spin_cf = r.reals(g + "/closed_form_spin_out");
    const auto et = r.reals(g + "/restitution_tangential");
    const auto et_cf = r.reals(g + "/closed_form_restitution_tangential");
    const auto mu = r.reals(g + "/friction");
    const auto overlap = r.reals(g + "/max_overlap");
    const double a = r.attribute(g, "radius");
    for (size_t k = 0; k < slides.size(); ++k) {
      ASSERT_TRUE(std::isfinite(ratio[k]) && std::isfinite(spin[k]) && std::isfinite(et[k]))
          << name << " " << k;
      if (slides[k] == 0.0 || mu[k] == 0.0) {
        EXPECT_LE(std::fabs(ratio[k]), mu[k] * 1.002 + 1e-12) << name << " " << k;
        continue;
      }
      ++sliding;
      // The scene limits friction with the elastic normal force: J_t = mu J_n (to the
      // integrator's error). The torque's lever is a - delta/2 where rigid-body theory has a:
      // spin change and contact slip differ from it by up to delta_max / a.
      const double lever = overlap[k] / a;
      EXPECT_NEAR(ratio[k] / ratio_cf[k], 1.0, 2e-3) << name << " " << k;
      EXPECT_NEAR((spin[k] - spin_in[k]) / (spin_cf[k] - spin_in[k]), 1.0, 0.5 * lever + 2e-3)
          << name << " " << k;
      EXPECT_NEAR(et[k], et_cf[k], std::fabs(1 + et_cf[k]) * lever + 4e-3) << name << " " << k;
    }
  }
  for (int test = 1; test <= 8; ++test) EXPECT_TRUE(seen[test]) << "test " << test;
  EXPECT_GE(sliding, 30);
  EXPECT_TRUE(std::filesystem::exists(opts.out_dir + "/summary.json"));
}
