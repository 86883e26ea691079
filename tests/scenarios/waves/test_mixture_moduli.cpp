// The mixture study's own pieces: the pair rules for two species against hand-computed
// values, the power-law fit on exact power laws, and the pressure servo on a small Hertzian
// glass packing (it must reach each target within its tolerance, on the loading branch).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>

#include "core/io/output.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/element_test.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/power_law_fit.hpp"
#include "scenarios/common/pressure_servo.hpp"
#include "scenarios/scene_registry.hpp"
#include "scenarios/waves/mixture_gas.hpp"
#include "scenarios/waves/mixture_materials.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

const char* kMaterials = R"(
[materials.glass]
shear_modulus = 29000.0
poisson = 0.3
density = 2540.0
tangential_stiffness = 1.0e4
viscosity = 100.0
friction = 0.5
[materials.rubber]
shear_modulus = 200.0
poisson = 0.5
density = 1270.0
tangential_stiffness = 150.0
viscosity = 100.0
friction = 0.5
)";

MixtureMaterials read_materials(const std::string& rule) {
  const SceneFile s = SceneFile::parse(
      std::string(kMaterials) + "[contact]\npair_rule = \"" + rule + "\"\n", "materials.toml");
  return MixtureMaterials::read(s);
}

}  // namespace

TEST(MixtureMaterials, PairRulesForGlassAndRubberMatchHandValues) {
  // Slots by name: glass 0, rubber 1. E = 2 G (1 + nu): 75400 and 600 MPa.
  const MixtureMaterials h = read_materials("harmonic");
  ASSERT_EQ(h.materials[0].name, "glass");
  EXPECT_DOUBLE_EQ(h.materials[0].young, 75400.0);
  EXPECT_DOUBLE_EQ(h.materials[1].young, 600.0);
  // 1/E* = (1 - 0.09)/75400 + (1 - 0.25)/600, whatever the rule.
  EXPECT_NEAR(h.effective_young(0, 0), 41428.571428571, 1e-6);
  EXPECT_NEAR(h.effective_young(0, 1), 792.349726776, 1e-8);
  EXPECT_NEAR(h.effective_young(1, 1), 400.0, 1e-10);

  const MixtureModel mh = h.model(), mp = h.model("product_over_sum");
  const auto &th = mh.tangential.table, &tp = mp.tangential.table;
  // k_t: harmonic 2 1e4 150 / 10150 = 295.5665..., product over sum 147.7833...
  EXPECT_NEAR(th(0, 1).kt, 295.566502463, 1e-8);
  EXPECT_NEAR(tp(0, 1).kt, 147.783251232, 1e-8);
  EXPECT_EQ(th(0, 1).kt, th(1, 0).kt);
  // Friction 0.5 with 0.5: 0.5 harmonic, 0.25 product over sum.
  EXPECT_DOUBLE_EQ(th(0, 1).mu_s, 0.5);
  EXPECT_DOUBLE_EQ(tp(0, 1).mu_s, 0.25);
  EXPECT_DOUBLE_EQ(tp(0, 1).mu_d, 0.25);
  // Like pairs keep their own values under both rules.
  for (const auto* t : {&th, &tp}) {
    EXPECT_DOUBLE_EQ((*t)(0, 0).kt, 1e4);
    EXPECT_DOUBLE_EQ((*t)(1, 1).kt, 150.0);
    EXPECT_DOUBLE_EQ((*t)(1, 1).mu_s, 0.5);
  }
  // Normal law: K = (4/3) E*, viscous coefficient 2 gamma (gamma sqrt(d delta), d = 4R),
  // gamma of unlike pairs 100 (harmonic) or 50 (product over sum).
  EXPECT_NEAR(mh.normal.table(0, 1).K, 4.0 / 3.0 * 792.349726776, 1e-8);
  EXPECT_EQ(mh.normal.table(0, 1).K, mp.normal.table(0, 1).K);
  EXPECT_TRUE(mh.normal.table(0, 1).reduced_radius);
  EXPECT_DOUBLE_EQ(mh.normal.table(0, 1).G, 200.0);
  EXPECT_DOUBLE_EQ(mp.normal.table(0, 1).G, 100.0);
  EXPECT_DOUBLE_EQ(mp.normal.table(0, 0).G, 200.0);
}

TEST(MixtureMaterials, ModulusReadingIsExplicitAndExclusive) {
  std::string text = std::string(kMaterials);
  granular::testing::replace_once(text, "shear_modulus = 200.0", "young_modulus = 600.0");
  const MixtureMaterials m = MixtureMaterials::read(SceneFile::parse(text, "young.toml"));
  EXPECT_EQ(m.materials[1].modulus_key, "young_modulus");
  EXPECT_DOUBLE_EQ(m.materials[1].young, 600.0);
  granular::testing::replace_once(text, "young_modulus = 600.0",
                                  "young_modulus = 600.0\nshear_modulus = 200.0");
  try {
    MixtureMaterials::read(SceneFile::parse(text, "both.toml"));
    ADD_FAILURE() << "both moduli must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("materials.rubber.shear_modulus"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("both.toml"), std::string::npos);
  }
}

TEST(MixtureMaterials, MindlinLawTakesItsSpringFromTheElasticConstantsNotAConstant) {
  // contact.tangential_law = "mindlin_modulus": k_t = 8 G* sqrt(R delta) with
  // 1/G* = (2 - nu_i)/G_i + (2 - nu_j)/G_j (G = 29000 and 200 MPa, nu = 0.3 and 0.5).
  std::string text = std::string(kMaterials);
  granular::testing::replace_once(text, "tangential_stiffness = 1.0e4\n", "");
  granular::testing::replace_once(text, "tangential_stiffness = 150.0\n", "");
  const MixtureMaterials m = MixtureMaterials::read(
      SceneFile::parse(text + "[contact]\ntangential_law = \"mindlin_modulus\"\n", "mindlin.toml"));
  const MixtureModel model = m.model();
  const auto& t = model.tangential.table;
  EXPECT_NEAR(t(0, 0).kt, 8 * 29000.0 / 3.4, 1e-9);
  EXPECT_NEAR(t(0, 1).kt, 1058.3941605839, 1e-8);  // whatever the pair rule: G* mixes
  EXPECT_EQ(t(0, 1).kt, m.model("product_over_sum").tangential.table(0, 1).kt);
  EXPECT_NEAR(t(1, 1).kt, 8 * 200.0 / 3.0, 1e-11);
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) EXPECT_EQ(t(a, b).law, CoulombTangential::MindlinReducedRadius);
  // The constant law stays the default, and a constant stiffness beside Mindlin is refused.
  EXPECT_EQ(read_materials("harmonic").model().tangential.table(0, 1).law,
            CoulombTangential::Constant);
  try {
    MixtureMaterials::read(SceneFile::parse(
        std::string(kMaterials) + "[contact]\ntangential_law = \"mindlin_modulus\"\n",
        "both.toml"));
    ADD_FAILURE() << "tangential_stiffness beside the Mindlin law must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("materials.glass.tangential_stiffness"),
              std::string::npos);
  }
}

TEST(PowerLawFit, RecoversExactPowerLaws) {
  const std::vector<double> P = {0.05, 0.1, 0.2, 0.5, 1.0, 2.0};
  for (double n : {1.0 / 3.0, 0.5, -0.25}) {
    std::vector<double> M;
    for (double p : P) M.push_back(734.0 * std::pow(p, n));
    const PowerLawFit f = fit_power_law(P, M);
    EXPECT_EQ(f.points, 6);
    EXPECT_NEAR(f.exponent, n, 1e-13);
    EXPECT_NEAR(f.prefactor, 734.0, 1e-10);
    EXPECT_LT(f.exponent_stderr, 1e-12);
  }
  // Non-positive moduli (unjammed states) are left out; two points give no standard error.
  const PowerLawFit two = fit_power_law({0.1, 0.4, 1.0}, {0.0, 2.0, 5.0});
  EXPECT_EQ(two.points, 2);
  EXPECT_NEAR(two.exponent, std::log(2.5) / std::log(2.5), 1e-14);
  EXPECT_TRUE(std::isnan(two.exponent_stderr));
  // Standard error against the hand formula: x = e^{0,1,2}, y residuals +-d, -2d at the ends.
  const double d = 0.01;
  const PowerLawFit r = fit_power_law({1.0, std::exp(1.0), std::exp(2.0)},
                                      {std::exp(d), std::exp(0.5 - 2 * d), std::exp(1.0 + d)});
  // log y = 0.5 log x + (d, -2d, d): slope 0.5 exactly, s^2 = 6 d^2 / 1, Sxx = 2.
  EXPECT_NEAR(r.exponent, 0.5, 1e-13);
  EXPECT_NEAR(r.exponent_stderr, std::sqrt(6 * d * d / 2), 1e-12);
}

// The chains' near-source decay is fitted both ways over the same beads: each model must
// recover its own law exactly and leave a clearly larger residual on the other's.
TEST(PowerLawFit, ExponentialFitRecoversItsLawAndTellsItFromAPowerLaw) {
  std::vector<double> d, ex, pw;
  for (int k = 1; k <= 200; ++k) {
    d.push_back(k);
    ex.push_back(0.02 * std::exp(-0.05 * k));
    pw.push_back(0.3 * std::pow(k, -1.7));
  }
  const PowerLawFit e = fit_exponential(d, ex);
  EXPECT_EQ(e.points, 200);
  EXPECT_NEAR(e.exponent, -0.05, 1e-14);
  EXPECT_NEAR(e.prefactor, 0.02, 1e-14);
  EXPECT_LT(e.rms_log_residual, 1e-12);
  EXPECT_GT(fit_power_law(d, ex).rms_log_residual, 0.3);
  EXPECT_NEAR(fit_power_law(d, pw).exponent, -1.7, 1e-13);
  EXPECT_GT(fit_exponential(d, pw).rms_log_residual, 0.3);
  // Abscissae of any sign; zero ordinates (no logarithm) are left out.
  const PowerLawFit s =
      fit_exponential({-1.0, 0.0, 1.0, 2.0}, {std::exp(0.5), 1.0, 0.0, std::exp(-1.0)});
  EXPECT_EQ(s.points, 3);
  EXPECT_NEAR(s.exponent, -0.5, 1e-14);
}

TEST(PressureServo, ReachesTargetPressuresOnAHertzianGlassPacking) {
  // 250 glass beads (d = 3.8-4.2 mm), the study's contact law and time step.
  const MixtureModel model = read_materials("harmonic").model();
  GasSpec gas;
  gas.count = 250, gas.diameter_min = 3.8, gas.diameter_max = 4.2, gas.density = 2540.0;
  gas.phi = 0.3, gas.seed = 5;
  PeriodicBox box;
  HostParticles h = random_gas(gas, box);
  DemParams params;
  params.dt = 0.1, params.skin = 0.2, params.max_overlap = 0.3;
  const double m = 2540.0 * M_PI / 6 * 64;  // bead mass at d = 4
  params.damping.translational = m / 50.0, params.damping.rotational = 0.1 * m * 16 / 50.0;
  using System = DemSystem<Kokkos::DefaultExecutionSpace, MixtureModel>;
  System sys(Particles<Kokkos::DefaultExecutionSpace>::from_host(h), box, model, params);
  strain_to_phi(sys, 0.55, -1e-3 / 3, 500, nullptr);
  compress_to_pressure(sys, 0.5, 1e-4, 20, 0.74);
  double mass = 0;
  for (int i = 0; i < h.size(); ++i)
    mass += h.density[i] * 4.0 / 3 * M_PI * std::pow(h.radius[i], 3);
  ServoSettings s;
  s.tolerance = 0.02, s.ekin_ratio = 1e-3, s.max_cycles = 400;
  double phi_before = 0;
  for (double target : {0.5, 2.0}) {
    const ServoResult r = servo_to_pressure(sys, target, mass / sys.box().volume(), s);
    EXPECT_TRUE(r.converged) << target << " MPa: P = " << r.m.pressure << " after " << r.cycles;
    const Measurements now = sys.measure();
    EXPECT_LT(std::fabs(now.pressure / target - 1), s.tolerance) << now.pressure;
    EXPECT_LT(now.ekin / now.epot, s.ekin_ratio);
    EXPECT_GT(now.phi, phi_before);  // loading branch: denser at the higher pressure
    EXPECT_TRUE(is_jammed(now));
    phi_before = now.phi;
  }
}

namespace {
// A packing in closed form for the servo: Hertzian, P = C e^{3/2} in the volumetric strain e
// (its energy chosen so that the servo's affine estimates give back e and K = 3P/(2e)), which
// consolidates at a constant rate (creep: e loses `creep` per time unit at a fixed box), at
// rest (E_kin = 0).
struct CreepingPacking {
  double e = 0.002, creep = 0, C = 2e4;
  DemParams prm;
  PeriodicBox bx;
  CreepingPacking() {
    prm.dt = 0.1;
    for (double& l : bx.len) l = 40.0;
  }
  double rate = 0;  // the box's strain rate per axis (negative: compression)
  Measurements measure() const {
    Measurements m;
    m.volume = bx.volume();
    m.pressure = C * std::pow(e, 1.5);
    m.epot = e * m.pressure * m.volume / 2.5;
    return m;
  }
  void check_health(const Measurements&) const {}
  const DemParams& params() const { return prm; }
  const PeriodicBox& box() const { return bx; }
  void set_strain_rate(double r, double, double) { rate = r; }
  void step(long n) {
    for (long k = 0; k < n; ++k) e += (-3 * rate - creep) * prm.dt;
  }
};
}  // namespace

// A proportional servo chasing a packing that consolidates at a steady rate settles behind
// its target, by the pressure whose rate just matches the creep: here 9 % short with a 2 %
// band, so it never converges. Integral action accumulates that rate and reaches the band.
TEST(PressureServo, IntegralActionRemovesTheOffsetBehindACreepingPacking) {
  const double rho = 1.5e3, target = 0.1;
  ServoSettings s;
  s.tolerance = 0.02, s.ekin_ratio = 1e-3, s.response_crossings = 0.5, s.max_cycles = 400;
  CreepingPacking p;
  auto strain_at = [&](double P) { return std::pow(P / p.C, 2.0 / 3.0); };
  auto tc_at = [&](double P) {  // the servo's crossing time at pressure P
    Measurements m;
    m.volume = p.bx.volume(), m.pressure = P, m.epot = strain_at(P) * P * m.volume / 2.5;
    return crossing_time(m, rho, 40.0);
  };
  p.e = strain_at(0.5 * target);               // loaded from below, as the servo meets a packing
  p.creep = 0.1 * s.max_step / tc_at(target);  // a tenth of the servo's fastest rate
  // Steady state of the proportional servo: its rate (goal - q) e / q / (resp tc) equals the
  // creep, with q = P^{2/3}, goal = target^{2/3} and e = q / C^{2/3}: q = goal - creep resp
  // tc(P) C^{2/3}, solved by iteration (tc depends on P weakly).
  const double goal = std::pow(target, 2.0 / 3.0);
  double q = goal;
  for (int k = 0; k < 100; ++k)
    q = goal - p.creep * s.response_crossings * tc_at(std::pow(q, 1.5)) * std::pow(p.C, 2.0 / 3.0);
  const double steady = std::pow(q, 1.5);
  ASSERT_LT(steady / target - 1, -3 * s.tolerance);  // far outside the band

  CreepingPacking a = p;
  const ServoResult prop = servo_to_pressure(a, target, rho, s);
  EXPECT_FALSE(prop.converged);
  EXPECT_NEAR(prop.m.pressure, steady, 1e-3 * target) << "the offset the closed form predicts";

  s.integral_crossings = 1.0;
  CreepingPacking b = p;
  const ServoResult pi = servo_to_pressure(b, target, rho, s);
  EXPECT_TRUE(pi.converged) << "P = " << pi.m.pressure << " after " << pi.cycles << " checks";
  EXPECT_LT(std::fabs(pi.m.pressure / target - 1), s.tolerance);
}

TEST(MixtureModuliScene, ShippedSceneFilesRead) {
  for (const char* name : {"mixture_moduli.toml", "mixture_moduli_quick.toml"}) {
    const SceneFile s = SceneFile::load(granular::testing::shipped_scene_path(name));
    EXPECT_EQ(s.text("scene"), "mixture_moduli");
    EXPECT_NO_THROW(check_mixture_moduli(s)) << name;
  }
}

namespace {

// Runs the small mixture study of tests/resume/mixture_moduli.toml, as changed in `text`, into a
// fresh folder named `name`; returns the folder.
std::string run_small_mixture(const std::string& text, const std::string& name) {
  SceneFile scene = SceneFile::parse(text, name + ".toml");
  scene.text("scene");
  RunOptions opts;
  opts.out_dir = granular::testing::temp_dir(name);
  opts.progress = false, opts.charts = false;
  run_mixture_moduli(scene, opts);
  return opts.out_dir;
}

}  // namespace

// A state the servo did not bring to its target is not probed: its moduli are NaN, it is left
// out of the fits, and summary.json lists it; `preparation.probe_unconverged = true` probes it
// as it is. One servo check cannot bring E_kin/E_pot under 1e-12 after the approach, so every
// state of this small study is unconverged.
TEST(MixtureModuliScene, StateTheServoDidNotConvergeToIsNotProbedUnlessAskedFor) {
  std::string text = granular::testing::read_text(std::string(GRANULAR_SOURCE_DIR) +
                                                  "/tests/resume/mixture_moduli.toml");
  granular::testing::replace_once(text, "max_checks = 200", "max_checks = 1");
  granular::testing::replace_once(text, "ekin_ratio = 1.0e-3", "ekin_ratio = 1.0e-12");
  for (const bool asked : {false, true}) {
    std::string t = text;
    if (asked)
      granular::testing::replace_once(t, "max_checks = 1",
                                      "max_checks = 1\nprobe_unconverged = true");
    const std::string out = run_small_mixture(t, asked ? "mixture_asked" : "mixture_refused");
    const H5Reader h5(out + "/results.h5");
    const auto converged = h5.reals("/table/servo_converged");
    const auto jammed = h5.reals("/table/jammed"), probed = h5.reals("/table/probed");
    const auto M = h5.reals("/table/M"), n = h5.reals("/fits/M_exponent");
    ASSERT_EQ(M.size(), 3u);
    for (size_t i = 0; i < M.size(); ++i) {
      EXPECT_EQ(converged[i], 0.0) << i;
      ASSERT_EQ(jammed[i], 1.0) << i;  // a contact network: only the servo's verdict differs
      EXPECT_EQ(probed[i], asked ? 1.0 : 0.0) << i;
      if (asked)
        EXPECT_GT(M[i], 0.0) << i;
      else
        EXPECT_TRUE(std::isnan(M[i])) << i;
    }
    // One pressure per mixture: no exponent either way, but the refused states leave the
    // fit without a single point (its prefactor too is undefined).
    for (double e : n) EXPECT_TRUE(std::isnan(e));
    const std::string summary = granular::testing::read_text(out + "/summary.json");
    EXPECT_NE(summary.find("\"unconverged_states\": ["), std::string::npos);
    EXPECT_NE(summary.find(asked ? "\"probed\": true" : "\"probed\": false"), std::string::npos);
    std::filesystem::remove_all(out);
  }
}

// [analysis] skeleton = true adds the skeleton of every state to the table (and nothing
// without it): the pressure shares of the three contact types add up to 1, glass alone carries
// all of it on glass–glass contacts, and in the half-rubber mixture (16 of each bead) every
// glass–rubber contact is counted once from each side, so glass beads have as many rubber
// partners as rubber beads have glass partners.
TEST(MixtureModuliScene, SkeletonColumnsAddUpAndCountEachUnlikeContactFromBothSides) {
  const std::string text = granular::testing::read_text(std::string(GRANULAR_SOURCE_DIR) +
                                                        "/tests/resume/mixture_moduli.toml");
  for (const bool asked : {false, true}) {
    const std::string out =
        run_small_mixture(asked ? text + "\n[analysis]\nskeleton = true\n" : text,
                          asked ? "mixture_skeleton" : "mixture_no_skeleton");
    const H5Reader h5(out + "/results.h5");
    if (!asked) {
      EXPECT_FALSE(h5.has("/table/skeleton_share_stiff_stiff"));
      std::filesystem::remove_all(out);
      continue;
    }
    const auto nu = h5.reals("/table/soft_fraction");
    const auto gg = h5.reals("/table/skeleton_share_stiff_stiff");
    const auto gr = h5.reals("/table/skeleton_share_stiff_soft");
    const auto rr = h5.reals("/table/skeleton_share_soft_soft");
    const auto z_gr = h5.reals("/table/skeleton_z_stiff_soft");
    const auto z_rg = h5.reals("/table/skeleton_z_soft_stiff");
    const auto cluster = h5.reals("/table/skeleton_stiff_largest_cluster");
    ASSERT_EQ(nu.size(), 3u);  // glass, and the half-rubber mixture under both pair rules
    for (size_t i = 0; i < nu.size(); ++i) {
      EXPECT_NEAR(gg[i] + gr[i] + rr[i], 1.0, 1e-12) << i;
      EXPECT_GT(cluster[i], 0.0) << i;
      EXPECT_LE(cluster[i], 1.0) << i;
      if (nu[i] == 0.0) {
        EXPECT_EQ(gg[i], 1.0);
        EXPECT_TRUE(std::isnan(z_rg[i]));  // no rubber beads
      } else {
        EXPECT_GT(gr[i], 0.0) << i;
        EXPECT_EQ(z_gr[i], z_rg[i]) << i;  // 16 glass and 16 rubber beads
      }
    }
    std::filesystem::remove_all(out);
  }
}

// preparation.unload_from takes each sample up to that peak, settles it there (not recorded)
// and brings it down through decreasing pressures: each recorded state is at its own target
// within the servo's tolerance, below the peak, and the summary names the branch. Pressures
// that do not decrease, or a peak not above them, are refused naming the key.
TEST(MixtureModuliScene, UnloadingBranchComesDownFromItsPeakToEachTarget) {
  const std::string base = granular::testing::read_text(std::string(GRANULAR_SOURCE_DIR) +
                                                        "/tests/resume/mixture_moduli.toml");
  std::string text = base;
  granular::testing::replace_once(text, "pressures = [0.5]\ntolerance",
                                  "pressures = [0.5, 0.2]\nunload_from = 2.0\ntolerance");
  const std::string out = run_small_mixture(text, "mixture_unloading");
  const H5Reader h5(out + "/results.h5");
  const auto target = h5.reals("/table/pressure_target"), p = h5.reals("/table/pressure");
  const auto converged = h5.reals("/table/servo_converged");
  ASSERT_EQ(target.size(), 5u);  // two fractions x two pressures + the pair-rule sample's one
  for (size_t i = 0; i < target.size(); ++i) {
    EXPECT_TRUE(target[i] == 0.5 || target[i] == 0.2) << i;  // the peak is not recorded
    if (converged[i] == 1.0) {
      EXPECT_NEAR(p[i] / target[i], 1.0, 0.02) << i;
    }
  }
  EXPECT_GE(std::count(converged.begin(), converged.end(), 1.0), 4);
  const std::string summary = granular::testing::read_text(out + "/summary.json");
  EXPECT_NE(summary.find("on the unloading branch"), std::string::npos);
  std::filesystem::remove_all(out);

  const std::pair<std::string, std::string> bad[] = {
      {"pressures = [0.2, 0.5]\nunload_from = 2.0\ntolerance", "preparation.pressures"},
      {"pressures = [0.5, 0.2]\nunload_from = 0.4\ntolerance", "preparation.unload_from"}};
  for (const auto& [block, key] : bad) {
    std::string t = base;
    granular::testing::replace_once(t, "pressures = [0.5]\ntolerance", block);
    try {
      const SceneFile scene = SceneFile::parse(t, "bad_unloading.toml");
      scene.text("scene");
      check_mixture_moduli(scene);
      ADD_FAILURE() << key << ": the scene must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

// particles.from: a packing file that holds the very gas the scene would draw itself (written
// as a state group, species 0 glass and 1 rubber) runs bitwise as the generated sample does;
// the file's mixture is reported as its exact soft volume fraction. Keys that would draw the
// particles, and species the materials list does not name, are refused naming the key.
TEST(MixtureModuliScene, PackingFileHoldingTheScenesOwnGasRunsBitwiseAsTheGeneratedOne) {
  std::string base = granular::testing::read_text(std::string(GRANULAR_SOURCE_DIR) +
                                                  "/tests/resume/mixture_moduli.toml");
  granular::testing::replace_once(base, "soft_volume_fractions = [0.0, 0.5]",
                                  "soft_volume_fractions = [0.5]");
  granular::testing::replace_once(base, "[pair_rule_check]\nsoft_volume_fraction = 0.5\n", "");
  granular::testing::replace_once(base, "pressures = [0.5]\n\n[run]", "\n[run]");
  const std::string generated = run_small_mixture(base, "mixture_generated");

  // The scene's gas: 32 beads of 3.8-4.2 mm, seed 1, phi_gas 0.3, half of them rubber.
  GasSpec gas;
  gas.count = 32, gas.diameter_min = 3.8, gas.diameter_max = 4.2, gas.seed = 1, gas.phi = 0.3;
  const MixtureMaterials mats = read_materials("harmonic");
  PeriodicBox box;
  const HostParticles h = mixture_gas(gas, mats, 0, 1, 0.5, box);
  const std::string dir = granular::testing::temp_dir("mixture_packing");
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/gas.h5";
  {
    H5Writer w(file);
    write_state(w, "/final_state", Particles<Kokkos::DefaultExecutionSpace>::from_host(h), box,
                1.0);
    w.commit();
  }
  std::string text = base;
  granular::testing::replace_once(text, "soft_volume_fractions = [0.5]\n", "");
  granular::testing::replace_once(text, "phi_gas = 0.3\n", "");
  granular::testing::replace_once(
      text, "count = 32\ndiameter_min = 3.8\ndiameter_max = 4.2\nseed = 1\n",
      "from = \"" + file + "\"\nfrom_materials = [\"glass\", \"rubber\"]\n");
  const std::string from_file = run_small_mixture(text, "mixture_from_file");

  const H5Reader a(generated + "/results.h5"), b(from_file + "/results.h5");
  for (const char* column :
       {"pressure", "phi", "z_mean", "K", "G", "M", "servo_steps", "rho_bulk", "max_overlap"}) {
    const auto x = a.reals(std::string("/table/") + column);
    const auto y = b.reals(std::string("/table/") + column);
    ASSERT_EQ(x.size(), 1u) << column;
    ASSERT_EQ(y.size(), 1u) << column;
    EXPECT_EQ(x[0], y[0]) << column;  // bitwise
  }
  EXPECT_GT(b.reals("/table/M")[0], 0.0);
  EXPECT_EQ(a.reals("/table/soft_fraction")[0], 0.5);
  EXPECT_EQ(b.reals("/table/soft_fraction")[0], soft_volume_fraction(h, 1));
  EXPECT_NEAR(soft_volume_fraction(h, 1), 0.5, 0.1);
  std::filesystem::remove_all(generated);
  std::filesystem::remove_all(from_file);

  const std::pair<std::string, std::string> bad[] = {
      {"from_materials = [\"glass\"]", "particles.from_materials"},  // rubber beads unnamed
      {"from_materials = [\"glass\", \"rubber\"]\nseed = 2", "particles.seed"}};
  for (const auto& [block, key] : bad) {
    std::string t = text;
    granular::testing::replace_once(t, "from_materials = [\"glass\", \"rubber\"]", block);
    try {
      const SceneFile scene = SceneFile::parse(t, "bad_packing.toml");
      scene.text("scene");
      check_mixture_moduli(scene);
      ADD_FAILURE() << key << ": the scene must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}
