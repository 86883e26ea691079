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
#include <string>
#include <vector>

#include "core/dem/host_particles.hpp"
#include "core/io/output.hpp"
#include "core/lammps/lammps_data.hpp"
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

namespace {

// The elastic collision scene with MC-strain (gamma = 1) alone, at the shipped time steps
// divided by `divide`; returns the run's folder.
std::string elastic_mc_strain_run(double divide, const std::string& tag) {
  std::string text = shipped_scene("soft_collision.toml");
  replace_once(text, "restitution = 0.95", "restitution = 1.0");
  replace_once(text, "restitution = 0.7", "restitution = 1.0");
  replace_once(text, "classical = true", "classical = false");
  replace_once(text, "stress_beta = [1.0]", "stress_beta = []");
  std::ostringstream steps;
  steps.precision(17);
  steps << "time_steps = [" << 10.0 / divide << ", " << 20.0 / divide << "]";
  replace_once(text, "time_steps = [10.0, 20.0]", steps.str());
  RunOptions opts;
  opts.out_dir = temp_dir("soft_mc_strain_" + tag);
  opts.progress = false, opts.charts = false;
  run_soft_collision(parse(text, "soft_mc_strain_" + tag + ".toml"), opts);
  return opts.out_dir;
}

}  // namespace

// MC-strain feeds the previous step's forces into the overlap correction. Whether its energy
// gain in an elastic collision (1.4 % for three hydrogel spheres, 3.8 % for five at the shipped
// step) belongs to the model or to that explicit lag is told by the step: a lag error is
// first order in dt, a property of the model is not. Measured: the gain halves with each
// halving of dt (0.0142, 0.0071, 0.0035, 0.0018, 0.0009 down to dt/16), so it is the
// integration's. The runaway of five elastic rubber spheres is the model's: it happens at
// the same time whatever the step (1000, 950, 925, 900, 894 us), converging to a finite time.
TEST(SoftCollisionScene, McStrainEnergyGainIsFirstOrderInTheStepItsRunawayIsNot) {
  const char* kGains[] = {"/runs/three/hydrogel/mc_strain_gamma_1/kinetic_energy",
                          "/runs/five/hydrogel/mc_strain_gamma_1/kinetic_energy",
                          "/runs/three/rubber/mc_strain_gamma_1/kinetic_energy"};
  const char* kRunaway = "/runs/five/rubber/mc_strain_gamma_1/time";
  std::vector<std::vector<double>> gain(std::size(kGains));
  std::vector<double> runaway_time;
  for (double divide : {1.0, 2.0, 4.0}) {
    const H5Reader r(elastic_mc_strain_run(divide, std::to_string(int(divide))) + "/results.h5");
    for (size_t k = 0; k < std::size(kGains); ++k) {
      const auto ekin = r.reals(kGains[k]);
      gain[k].push_back(ekin.back() / ekin.front() - 1);
    }
    runaway_time.push_back(r.reals(kRunaway).back());
  }
  for (size_t k = 0; k < std::size(kGains); ++k) {
    EXPECT_GT(gain[k][0], 0.01) << kGains[k];  // a gain, and a sizeable one at the shipped step
    EXPECT_NEAR(gain[k][0] / gain[k][1], 2.0, 0.1) << kGains[k];
    EXPECT_NEAR(gain[k][1] / gain[k][2], 2.0, 0.1) << kGains[k];
  }
  // The five rubber spheres stop at the overlap limit well before the 6 ms end, at dt and at
  // dt/4 within 10 % of each other: no step makes the model stable.
  EXPECT_LT(runaway_time[0], 2000.0);
  EXPECT_LT(runaway_time[2], 2000.0);
  EXPECT_NEAR(runaway_time[2] / runaway_time[0], 1.0, 0.1);
}

namespace {

// The confined box around the packing of the test below: no gravity, the insertion region the
// box itself, classical Hertz only, `fill.from` in place of the random insertion, pressed
// slowly (0.01 m/s) to 6 % strain.
std::string fill_from_scene(const std::string& from, const std::string& fill_extra) {
  return "scene = \"confined_compression\"\n"
         "[materials.hydrogel]\nyoung_modulus = 0.0233\npoisson = 0.5\ndensity = 11.5\n"
         "friction = 0.03\nrestitution = 0.7\n"
         "[materials.wall]\nyoung_modulus = inf\npoisson = 0.3\nfriction = 0.03\n"
         "restitution = 0.7\n"
         "[contact]\ntangential = \"mindlin\"\ndamping = \"restitution_common\"\n"
         "[box]\nsize = [42.0, 42.0, 42.0]\n"
         "[fill]\nfrom = \"" +
         from + "\"\n" + fill_extra +
         "region_height = 42.0\ngravity = 0.0\ndamping_time = 2e4\nmax_time = 3e6\n"
         "[compression]\nparticle_material = \"hydrogel\"\nwall_material = \"wall\"\n"
         "strain = 0.06\nwall_speed = 1e-5\ntime_step = 10.0\nsample_every = 50\n"
         "[multicontact]\nclassical = true\nstrain_gamma = []\nstress_beta = []\n";
}

// Hertz overlap of normal force f: f = (4/3) E* sqrt(R*) delta^(3/2).
double hertz_overlap(double f, double e_star, double r_star) {
  return std::pow(3 * f / (4 * e_star * std::sqrt(r_star)), 2.0 / 3.0);
}

}  // namespace

// fill.from settles a packing from a file instead of a random insertion. Eight spheres on a
// simple cubic lattice that fills the 2d box (radii a hair short of it, so that nothing
// touches at the start) make four columns of two spheres between floor and top wall. Pressed
// slowly, each column is three Hertz contacts in series (sphere-floor, sphere-sphere,
// sphere-top wall) carrying one force F, so the top wall's push u = 2 delta_wall(F) +
// delta_pair(F) and its force is 4F: the closed form is met only by that lattice, not by a
// random packing of the same spheres. At 0.01 m/s with restitution 0.7 the force stays within
// 0.3 % of it (at 0.1 m/s and 0.95 the columns ring by +-10 %).
TEST(ConfinedCompressionScene, FillFromAFileCompressesThatLatticeAsHertzColumnsInSeries) {
  const double a = 10.5 * (1 - 1e-9);
  HostParticles h;
  h.resize(8);
  for (int i = 0; i < 8; ++i) {
    h.x[i] = (i & 1) ? 31.5 : 10.5, h.y[i] = (i & 2) ? 31.5 : 10.5, h.z[i] = (i & 4) ? 31.5 : 10.5;
    h.radius[i] = a, h.density[i] = 2000;  // the scene's hydrogel density replaces it
  }
  const double lo[3] = {0, 0, 0}, len[3] = {42, 42, 42};
  const std::string dir = temp_dir("fill_from");
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir + "/lattice.data");
    f << lammps_data_text(h, lo, len);
  }
  RunOptions opts;
  opts.out_dir = dir + "/run";
  opts.progress = false, opts.charts = false;
  run_confined_compression(parse(fill_from_scene(dir + "/lattice.data", ""), "fill_from.toml"),
                           opts);
  const std::string summary = granular::testing::read_text(opts.out_dir + "/summary.json");
  const auto at = summary.find("\"volume_fraction_box\"");
  ASSERT_NE(at, std::string::npos) << summary;
  const double phi = std::stod(summary.substr(summary.find(':', at) + 1));
  EXPECT_NEAR(phi, 8 * 4.0 / 3.0 * M_PI * a * a * a / (42.0 * 42 * 42), 1e-12);

  const H5Reader r(opts.out_dir + "/results.h5");
  const auto strain = r.reals("/runs/classical/strain");
  const auto force = r.reals("/runs/classical/top_wall_force");
  const double e = 0.0233, nu = 0.5;
  const double e_wall = e / (1 - nu * nu), e_pair = e / (2 * (1 - nu * nu));
  const double gap = 2 * (10.5 - a) * 2;  // what the lattice leaves free along a column
  size_t checked = 0;
  for (size_t k = 0; k < strain.size(); ++k) {
    const double u = strain[k] * 42.0 - gap;
    if (strain[k] < 0.02 || (k + 1 < strain.size() && strain[k + 1] < strain[k])) continue;
    double f_lo = 0, f_hi = 1e3;  // N; bisection on u(F) = 2 delta_wall + delta_pair
    for (int it = 0; it < 200; ++it) {
      const double f = 0.5 * (f_lo + f_hi);
      const double uf = 2 * hertz_overlap(f, e_wall, a) + hertz_overlap(f, e_pair, a / 2);
      (uf < u ? f_lo : f_hi) = f;
    }
    EXPECT_NEAR(force[k] / (4 * f_lo), 1.0, 0.01) << "strain " << strain[k];
    ++checked;
  }
  EXPECT_GT(checked, 20u);
}

// The file gives the particles: the keys that would draw them are refused beside it, and a
// particle outside the box is refused naming fill.from.
TEST(ConfinedCompressionScene, FillFromRefusesDrawingKeysAndParticlesOutsideTheBox) {
  HostParticles h;
  h.resize(2);
  h.x = {10, 30}, h.y = {10, 10}, h.z = {10, 50};  // the second above the 42 mm region
  h.radius = {5, 5}, h.density = {1000, 1000};
  const double lo[3] = {0, 0, 0}, len[3] = {42, 42, 60};
  const std::string dir = temp_dir("fill_from_bad");
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir + "/outside.data");
    f << lammps_data_text(h, lo, len);
  }
  const std::pair<std::string, std::string> cases[] = {
      {"count = 8\n", "fill.count"},
      {"diameter_spread = 0.1\n", "fill.diameter_spread"},
      {"", "fill.from"}};
  for (const auto& [extra, key] : cases) {
    RunOptions opts;
    opts.check_only = true;
    try {
      run_confined_compression(
          parse(fill_from_scene(dir + "/outside.data", extra), "fill_from_bad.toml"), opts);
      ADD_FAILURE() << key << ": the scene must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("fill_from_bad.toml"), std::string::npos) << e.what();
    }
  }
}
