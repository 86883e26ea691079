// The soft-particle scenes against closed forms. Three spheres in a row with the outer two
// launched symmetrically at the centre one: by symmetry the centre never moves, so with
// classical Hertz each outer sphere makes a head-on impact on a fixed sphere (reduced mass
// m, not the pair's m/2). Elastic: the largest overlap is Hertz's with m* = m and R* = a/2,
// and no energy is lost. Damped: the restitution mapping sets the damping for the pair's
// reduced mass m/2, so against a fixed partner the damping ratio is 1/sqrt 2 of the mapped
// one and the kinetic energy left is e'^2 of that ratio. Scene-file errors name key and file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "granular_config.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::replace_once;
using granular::testing::shipped_scene;
using granular::testing::temp_dir;

namespace {

// The shipped three/five-sphere scene sampled every step.
std::string classical_collision_scene() {
  std::string text = shipped_scene("soft_collision.toml");
  replace_once(text, "sample_every = 5", "sample_every = 1");
  return text;
}

struct Material {
  const char* name;
  double young, poisson, density, restitution;
};
// As in soft_collision.toml (E in N/mm^2, density in ug/mm^3).
const Material kHydrogel{"hydrogel", 0.0233, 0.5, 11.5, 0.95};
const Material kRubber{"rubber", 1.85, 0.46, 2000, 0.7};

// As the command line does: the driver's name is read before the driver checks the rest.
SceneFile parse(const std::string& text, const std::string& name) {
  SceneFile scene = SceneFile::parse(text, name);
  (void)scene.text("scene");
  return scene;
}

double max_of(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

}  // namespace

TEST(SoftCollisionScene, ElasticThreeInARowIsHertzImpactOnAFixedSphere) {
  std::string text = classical_collision_scene();
  replace_once(text, "restitution = 0.95", "restitution = 1.0");
  RunOptions opts;
  opts.out_dir = temp_dir("soft_elastic");
  opts.progress = false, opts.charts = false;
  run_soft_collision(parse(text, "soft_elastic.toml"), opts);
  const H5Reader r(opts.out_dir + "/results.h5");
  const double a = r.attribute("/", "radius"), v = 0.01;
  // Hydrogel only: elastic rubber at 10 m/s would overlap by 0.98 a, past the guard.
  for (const Material& m : {kHydrogel}) {
    const std::string g = std::string("/runs/three/") + m.name + "/classical";
    const auto ekin = r.reals(g + "/kinetic_energy");
    const auto overlap = r.reals(g + "/centre_overlap");
    const double mass = m.density * 4.0 / 3.0 * M_PI * a * a * a;
    const double e_star = m.young / (2 * (1 - m.poisson * m.poisson));
    const double delta =
        std::pow(15 * mass * v * v / (16 * e_star * std::sqrt(0.5 * a)), 0.4);  // m* = m
    EXPECT_NEAR(max_of(overlap) / delta, 1.0, 5e-4) << m.name;
    EXPECT_NEAR(ekin.back() / ekin.front(), 1.0, 1e-6) << m.name;
    EXPECT_EQ(overlap.back(), 0.0) << m.name;  // the collision is over
  }
}

TEST(SoftCollisionScene, DampedThreeInARowKeepsTheEnergyOfHalfTheReducedMassDamping) {
  RunOptions opts;
  opts.out_dir = temp_dir("soft_damped");
  opts.progress = false, opts.charts = false;
  run_soft_collision(parse(classical_collision_scene(), "soft_damped.toml"), opts);
  const H5Reader r(opts.out_dir + "/results.h5");
  for (const Material& m : {kHydrogel, kRubber}) {
    const auto ekin = r.reals(std::string("/runs/three/") + m.name + "/classical/kinetic_energy");
    // The law is a linear oscillator in disguise: e = exp(-pi z / sqrt(1 - z^2)).
    const double l = std::log(m.restitution);
    const double zeta = -l / std::sqrt(l * l + M_PI * M_PI) / std::sqrt(2.0);
    const double e_fixed = std::exp(-M_PI * zeta / std::sqrt(1 - zeta * zeta));
    EXPECT_NEAR(ekin.back() / ekin.front() / (e_fixed * e_fixed), 1.0, 2e-3) << m.name;
    // Against the pair's own restitution the difference is several per cent.
    EXPECT_GT(ekin.back() / ekin.front(), m.restitution * m.restitution * 1.02) << m.name;
  }
}

TEST(ConfinedCompressionScene, ErrorsNameTheKeyAndTheFile) {
  const std::string base = shipped_scene("confined_compression_quick.toml");
  const std::pair<std::string, std::string> mutants[] = {
      {"wall_speed = 1e-4", "wal_speed = 1e-4"},  // misspelt: wall_speed is missing
      {"max_time = 3e6", "max_time = 1e4"},       // shorter than the fall
      {"strain = 0.134", "strain = nan"},         // not a strain
      {"particle_material = \"hydrogel\"", "particle_material = \"glass\""}};
  const char* keys[] = {"compression.wall_speed", "fill.max_time", "compression.strain",
                        "compression.particle_material"};
  for (size_t k = 0; k < std::size(mutants); ++k) {
    std::string text = base;
    replace_once(text, mutants[k].first, mutants[k].second);
    RunOptions opts;
    opts.out_dir = temp_dir("confined_bad");
    opts.progress = false, opts.charts = false;
    try {
      run_confined_compression(parse(text, "bad_box.toml"), opts);
      ADD_FAILURE() << keys[k] << ": the run must stop";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(keys[k]), std::string::npos) << what;
      EXPECT_NE(what.find("bad_box.toml"), std::string::npos) << what;
    }
    EXPECT_FALSE(std::filesystem::exists(opts.out_dir + "/summary.json"));
  }
}

// Elastic rubber at 15 m/s presses classical Hertz past the scene's overlap limit of 1.3 a
// (0.98 a at 10 m/s, and the Hertz overlap grows as v^(4/5)); hydrogel stays below it (0.70 a
// at 10 m/s). The rubber curve ends there with the reason in summary.json, and the scene goes
// on to the other runs (it used to stop the scene). Empty multi-contact lists run the
// classical model alone.
TEST(SoftCollisionScene, ModelPastTheOverlapLimitEndsItsOwnCurveNotTheScene) {
  std::string text = classical_collision_scene();
  replace_once(text, "restitution = 0.95", "restitution = 1.0");
  replace_once(text, "restitution = 0.7", "restitution = 1.0");
  replace_once(text, "speed = 0.01 ", "speed = 0.015 ");
  replace_once(text, "strain_gamma = [1.0]", "strain_gamma = []");
  replace_once(text, "stress_beta = [1.0]", "stress_beta = []");
  RunOptions opts;
  opts.out_dir = temp_dir("soft_past_limit");
  opts.progress = false, opts.charts = false;
  ASSERT_NO_THROW(run_soft_collision(parse(text, "soft_past_limit.toml"), opts));
  const std::string summary = granular::testing::read_text(opts.out_dir + "/summary.json");
  const auto rubber = summary.find("\"three/rubber/classical\"");
  const auto hydrogel = summary.find("\"three/hydrogel/classical\"");
  ASSERT_NE(rubber, std::string::npos) << summary;
  ASSERT_NE(hydrogel, std::string::npos) << summary;
  const auto ended = summary.find("\"ended_early\"", rubber);
  ASSERT_NE(ended, std::string::npos) << summary;
  EXPECT_LT(ended, summary.find('}', rubber));  // in the rubber run's own entry
  EXPECT_EQ(summary.find("\"ended_early\"", hydrogel) < summary.find('}', hydrogel), false);
  EXPECT_EQ(summary.find("mc_strain"), std::string::npos);  // no multi-contact model ran
  EXPECT_EQ(summary.find("mc_stress"), std::string::npos);
  const H5Reader r(opts.out_dir + "/results.h5");
  const auto t = r.reals("/runs/three/rubber/classical/time");
  const auto th = r.reals("/runs/three/hydrogel/classical/time");
  EXPECT_LT(t.size(), th.size());  // the rubber curve stops at the limit
}

// A model list may be empty; no model at all is refused, naming the key.
TEST(SoftCollisionScene, NoModelAtAllIsRefusedNamingTheKey) {
  std::string text = shipped_scene("soft_collision.toml");
  replace_once(text, "classical = true", "classical = false");
  replace_once(text, "strain_gamma = [1.0]", "strain_gamma = []");
  replace_once(text, "stress_beta = [1.0]", "stress_beta = []");
  RunOptions opts;
  opts.check_only = true;
  try {
    run_soft_collision(parse(text, "no_model.toml"), opts);
    FAIL() << "a scene without a model was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("multicontact.classical"), std::string::npos) << e.what();
  }
  replace_once(text, "classical = false", "classical = true");
  EXPECT_NO_THROW(run_soft_collision(parse(text, "classical_only.toml"), opts));
}
