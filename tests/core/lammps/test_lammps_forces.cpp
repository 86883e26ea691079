// The LAMMPS force reference on its own (LAMMPS itself is compared in tests/lammps/): closed
// forms of two-sphere contacts, the tangential history's life, periodic images of a sheared
// box, and every malformed model rejected with a message that says what is accepted; the
// scene refuses a run whose recorded states would not fit in memory.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/lammps/lammps_data.hpp"
#include "core/lammps/lammps_forces.hpp"
#include "core/run/error.hpp"
#include "granular_config.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

// Two spheres along x in a large cubic box (SI-like numbers).
LammpsData two_spheres(double gap, double vrel_x, double vrel_y = 0) {
  LammpsData d;
  d.atom_types = 1;
  for (int k = 0; k < 3; ++k) d.lo[k] = 0, d.len[k] = 0.01;
  HostParticles& h = d.particles;
  h.resize(2);
  const double r = 5e-4;
  for (int i = 0; i < 2; ++i) h.radius[i] = r, h.density[i] = 2500.0, h.y[i] = h.z[i] = 0.005;
  h.x[0] = 0.005 - 0.5 * (2 * r - gap), h.x[1] = 0.005 + 0.5 * (2 * r - gap);
  h.vx[0] = 0.5 * vrel_x, h.vx[1] = -0.5 * vrel_x;  // approaching for vrel_x > 0
  h.vy[0] = 0.5 * vrel_y, h.vy[1] = -0.5 * vrel_y;
  d.ids = {1, 2};
  return d;
}

LammpsPairModel model(const std::string& style, const std::vector<std::string>& coeffs,
                      int ntypes = 1) {
  return parse_lammps_pair(style, coeffs, ntypes, lammps_units("si"));
}

double mass(double r) { return 2500.0 * (4.0 * M_PI / 3.0 * r * r * r); }

// The part of the force on atom 0 across the line of centres (the normal force turns with the
// pair, so its y component is not zero once the atoms have moved).
double tangential_y(const LammpsForceField& ff) {
  double n[3], len = 0;
  for (int k = 0; k < 3; ++k) n[k] = ff.x[k] - ff.x[3 + k], len += n[k] * n[k];
  len = std::sqrt(len);
  double fn = 0;
  for (int k = 0; k < 3; ++k) n[k] /= len, fn += ff.force[k] * n[k];
  return ff.force[1] - fn * n[1];
}

}  // namespace

TEST(LammpsForces, GranHookeHeadOnIsSpringMinusMassScaledDashpot) {
  const double overlap = 4e-5, v = 0.2, kn = 2000, gn = 5e4;
  LammpsForceField ff(two_spheres(overlap, v),
                      model("gran/hooke 2000 NULL 5e4 NULL 0.5 1", {"* *"}), lammps_units("si"),
                      1e-7);
  ff.compute(false);
  const double meff = 0.5 * mass(5e-4);
  // Particle 1 sits at smaller x: pushed towards -x, the dashpot adds to the approach.
  const double expect = -(kn * overlap + meff * gn * v);
  EXPECT_NEAR(ff.force[0], expect, 1e-12 * std::fabs(expect));
  EXPECT_NEAR(ff.force[3], -expect, 1e-12 * std::fabs(expect));
  EXPECT_EQ(ff.contacts, 1);
  // Pair virial xx = del_x f_x with del = x_1 - x_2 = -(2r - overlap).
  EXPECT_NEAR(ff.virial[0], -(1e-3 - overlap) * expect, 1e-12 * std::fabs(ff.virial[0]));
}

TEST(LammpsForces, HertzMaterialIsFourThirdsEstarSqrtRDeltaTimesDelta) {
  const double overlap = 5e-5, E = 1e8, nu = 0.3;
  LammpsForceField ff(
      two_spheres(overlap, 0.0),
      model("granular", {"* * hertz/material 1e8 0 0.3 tangential linear_nohistory 0 0.5"}),
      lammps_units("si"), 1e-7);
  ff.compute(false);
  const double estar = E / (2 * (1 - nu * nu)), R = 0.5 * 5e-4;
  const double expect = 4.0 / 3.0 * estar * std::sqrt(R * overlap) * overlap;
  EXPECT_NEAR(-ff.force[0], expect, 1e-12 * expect);
}

TEST(LammpsForces, StickingSpringGrowsAsKtVtTimesAndIsForgottenWhenTheContactEnds) {
  // Tangential sliding at constant relative speed, no dashpot (dampflag 0), no friction
  // limit reached: after k steps the spring holds kt * v_t * k dt.
  const double overlap = 4e-5, vt = 1e-3, kt = 1500, dt = 1e-8;
  LammpsForceField ff(two_spheres(overlap, 0.0, vt),
                      model("gran/hooke/history 2000 1500 0 0 10 0", {"* *"}), lammps_units("si"),
                      dt);
  ff.compute(false);
  EXPECT_EQ(ff.force[1], 0.0);  // setup: no history yet, no dashpot
  // In three steps the spring's torque spins the atoms up by ~1e-6 rad/s, which slows the
  // sliding of the surfaces by ~1e-6 of v_t: the closed form holds to that.
  for (int k = 1; k <= 3; ++k) {
    ff.step();
    EXPECT_NEAR(tangential_y(ff), -kt * vt * k * dt, 1e-5 * kt * vt * k * dt) << "step " << k;
  }
  // Pull the pair apart: the contact ends, and a new touch starts from an empty spring.
  ff.x[0] -= 1e-4;
  ff.compute(true);
  EXPECT_EQ(ff.contacts, 0);
  ff.x[0] += 1e-4;
  ff.compute(false);
  EXPECT_EQ(ff.contacts, 1);
  EXPECT_NEAR(tangential_y(ff), 0.0, 1e-9 * kt * vt * dt);
}

TEST(LammpsForces, TiltByAWholeEdgeGivesTheOrthogonalBoxForces) {
  // xy = lx and yz = ly describe the same periodic lattice as the orthogonal box: every
  // contact across the sheared faces must find the same image.
  LammpsData d = read_lammps_data(
      std::string(GRANULAR_SOURCE_DIR) + "/tests/lammps/data/orthogonal.data", 1, 1, 1);
  const auto m = model("granular",
                       {"* * hooke 2000 0.02 tangential linear_history 1500 0.5 0.5 "
                        "damping velocity"},
                       2);
  LammpsForceField a(d, m, lammps_units("si"), 5e-7);
  d.tilt[0] = d.len[0], d.tilt[2] = d.len[1];
  LammpsForceField b(d, m, lammps_units("si"), 5e-7);
  a.compute(false), b.compute(false);
  for (int s = 0; s < 10; ++s) a.step(), b.step();
  EXPECT_EQ(a.contacts, b.contacts);
  EXPECT_GT(a.contacts, 100);
  double fmax = 0, diff = 0;
  for (int i = 0; i < 3 * a.size(); ++i)
    fmax = std::max(fmax, std::fabs(a.force[i])),
    diff = std::max(diff, std::fabs(a.force[i] - b.force[i]));
  EXPECT_LT(diff, 1e-12 * fmax);
}

TEST(LammpsForces, MalformedModelsAreRefusedSayingWhatIsAccepted) {
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([] { model("lj/cut 2.5", {"* *"}); }).find("gran/hooke/history"),
            std::string::npos);
  EXPECT_NE(message([] { model("gran/hooke 2000 NULL 5e4", {"* *"}); }).find("dampflag"),
            std::string::npos);
  EXPECT_NE(message([] { model("gran/hooke 2000 NULL 5e4 NULL 0.5 2", {"* *"}); }).find("0 or 1"),
            std::string::npos);
  EXPECT_NE(message([] { model("granular", {"* * hooke 1 1"}); }).find("tangential"),
            std::string::npos);
  EXPECT_NE(message([] {
              model("granular", {"* * hooke 1 1 tangential mindlin NULL 1 0.5"});
            }).find("hertz/material"),
            std::string::npos);
  EXPECT_NE(message([] {
              model("granular", {"* * jkr 1 1 0.3 1 tangential linear_history 1 1 1"});
            }).find("not supported"),
            std::string::npos);
  EXPECT_NE(message([] {
              model("granular",
                    {"1 1 hooke 1 1 tangential linear_history 1 1 1",
                     "2 2 hooke 1 1 tangential linear_history 1 1 1"},
                    2);
            }).find("set the pair explicitly"),
            std::string::npos);
  EXPECT_NE(message([] { model("gran/hooke 1 NULL 1 NULL 0.5 1", {"1 3"}, 2); }).find("outside"),
            std::string::npos);
  EXPECT_NE(message([] { lammps_units("furlongs"); }).find("metal"), std::string::npos);
  // A box narrower than one contact distance would let a particle touch its own image.
  LammpsData d = two_spheres(4e-5, 0);
  d.len[2] = 9e-4;
  EXPECT_NE(message([&] {
              LammpsForceField(d, model("gran/hooke 1 NULL 1 NULL 0.5 1", {"* *"}),
                               lammps_units("si"), 1e-7);
            }).find("larger box"),
            std::string::npos);
}

// Every recorded state of the scene stays in memory until the run is written: a deck whose
// run.steps / run.output_every would hold terabytes (here 20000 atoms, a million states) is
// refused before anything is built or written, naming both settings and the file. The box is
// also too narrow for the spheres, so that without the guard the run is refused for
// lammps.data (and this test fails) instead of recording states until memory runs out.
TEST(LammpsForces, SceneRefusesARunWhoseStatesWouldNotFitInMemory) {
  const int n = 20000;
  HostParticles h;
  h.resize(n);
  for (int i = 0; i < n; ++i) {
    h.radius[i] = 5e-4, h.density[i] = 2500.0;
    h.x[i] = 2e-3 * (i % 100 + 0.5), h.y[i] = 2e-3 * (i / 100 + 0.5), h.z[i] = 4.5e-4;
  }
  const double lo[3] = {0, 0, 0}, len[3] = {0.2, 0.4, 9e-4};
  const std::string dir = granular::testing::temp_dir("lammps_states_guard");
  std::filesystem::create_directories(dir);
  const std::string data = dir + "/wide.data", deck = dir + "/too_many_states.toml";
  std::ofstream(data) << lammps_data_text(h, lo, len, {}, 1.0, 1.0, 1.0);
  std::ofstream(deck) << "scene = \"lammps_forces\"\n[lammps]\ndata = \"" << data
                      << "\"\nunits = \"si\"\npair_style = \"gran/hooke 2000 NULL 5e4 NULL 0.5 "
                         "1\"\npair_coeff = [\"* *\"]\ntimestep = 1e-7\n[run]\nsteps = "
                         "1000000\noutput_every = 1\n";
  RunOptions opts;
  opts.out_dir = dir + "/out";
  opts.progress = false, opts.charts = false;
  std::string what = "no error";
  try {
    run_lammps_forces(SceneFile::load(deck), opts);
  } catch (const InputError& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("'run.steps'"), std::string::npos) << what;
  EXPECT_NE(what.find("run.output_every"), std::string::npos) << what;
  EXPECT_NE(what.find(deck), std::string::npos) << what;
  EXPECT_FALSE(std::filesystem::exists(opts.out_dir));
}
