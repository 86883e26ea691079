// Saved configurations (checkpoints of relaxed packings): the HDF5 round trip is bitwise,
// probing a configuration read back from its file gives exactly the moduli the preparing
// run measured on it (which needs the contact history to be restored), and probing from a
// saved state against an unstrained reference run removes the drift of a packing that is
// still relaxing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/io/output.hpp"
#include "core/lammps/lammps_data.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/element_test.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/moduli/moduli_outputs.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::shipped_scene;
using granular::testing::temp_dir;

namespace {
using Exec = Kokkos::DefaultExecutionSpace;
using Frictional = ContactModel<LinearNormal, CoulombTangential>;

const char* kCommon = R"(
[contact]
normal = "linear"
kn = 1.0e5
gamma_n = 1000.0
tangential = "coulomb"
kt = 8.0e4
gamma_t = 200.0
mu = 0.5
[damping]
background = 100.0
rotational = 20.0
[probe]
amplitude = 3.0e-6
strain_steps = 200
relax_steps = 200
[run]
dt = 0.004
skin = 0.2
)";

const char* kPrepare = R"(
scene = "elastic_moduli"
[particles]
count = 120
diameter_min = 1.0
diameter_max = 3.0
density = 2000.0
seed = 3
[preparation]
phi_gas = 0.45
phi_0 = 0.5
phi_max = 0.72
volumetric_strain_rate = 2.0e-2
targets = [0.68]
relax_ratio = 1.0e-6
relax_max_steps = 2000
)";

// As the CLI does: the `scene` key picks the driver before the driver reads the rest.
SceneFile scene(const std::string& text, const std::string& name) {
  SceneFile s = SceneFile::parse(text, name);
  EXPECT_EQ(s.text("scene"), "elastic_moduli");
  return s;
}

std::vector<double> column(const std::string& dir, const std::string& name) {
  return H5Reader(dir + "/results.h5").reals("/table/" + name);
}

// A small frictional packing, compressed until it carries contacts with tangential history.
DemSystem<Exec, Frictional> compressed_packing(std::vector<double>& density) {
  GasSpec g;
  g.count = 100, g.density = 2000, g.seed = 5, g.phi = 0.45;
  PeriodicBox box;
  const HostParticles h = random_gas(g, box);
  density = h.density;
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.2, prm.damping.translational = 100, prm.damping.rotational = 20;
  const Frictional model{
      LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.5), {}};
  DemSystem<Exec, Frictional> sys(Particles<Exec>::from_host(h), box, model, prm);
  strain_to_phi(sys, 0.68, -3e-2 / 3, 500, nullptr);
  sys.step(200);
  return sys;
}
}  // namespace

TEST(SavedConfigurations, HdfRoundTripIsBitwiseIncludingContactHistory) {
  std::vector<double> density;
  auto sys = compressed_packing(density);
  const ConfigState a = snapshot(sys, density, sys.measure().pressure);
  ASSERT_EQ(a.history_width, 3);
  ASSERT_GT(a.pair_i.size(), 50u);  // contacts with a tangential spring
  const auto path = granular::testing::unique_temp_path("granular_config_roundtrip.h5");
  write_config(path.string(), a);
  const ConfigState b = read_config(path.string());
  std::filesystem::remove(path);
  EXPECT_EQ(a.particles.x, b.particles.x);
  EXPECT_EQ(a.particles.y, b.particles.y);
  EXPECT_EQ(a.particles.z, b.particles.z);
  EXPECT_EQ(a.particles.vx, b.particles.vx);
  EXPECT_EQ(a.particles.vy, b.particles.vy);
  EXPECT_EQ(a.particles.vz, b.particles.vz);
  EXPECT_EQ(a.particles.radius, b.particles.radius);
  EXPECT_EQ(a.particles.density, b.particles.density);
  EXPECT_EQ(a.particles.species, b.particles.species);
  EXPECT_EQ(a.w, b.w);
  EXPECT_EQ(a.mass, b.mass);
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(a.box.lo[d], b.box.lo[d]);
    EXPECT_EQ(a.box.len[d], b.box.len[d]);
  }
  EXPECT_EQ(a.pair_i, b.pair_i);
  EXPECT_EQ(a.pair_j, b.pair_j);
  EXPECT_EQ(a.history, b.history);
  EXPECT_EQ(a.phi, b.phi);
  EXPECT_EQ(a.pressure, b.pressure);

  // Restarts from memory and from the file are the same state, bitwise; it is the running
  // state up to the re-evaluation of sliding springs with end-of-step velocities; the
  // masses rebuilt from radius and density are the saved ones.
  using System = DemSystem<Exec, Frictional>;
  auto ra = restart_system<System>(a, sys.model(), sys.params());
  auto rb = restart_system<System>(b, sys.model(), sys.params());
  const Measurements m0 = sys.measure(), ma = ra.measure(), mb = rb.measure();
  for (int q = 0; q < 6; ++q) {
    EXPECT_EQ(ma.stress[q], mb.stress[q]);
    EXPECT_NEAR(ma.stress[q], m0.stress[q], 1e-4 * m0.pressure);
  }
  EXPECT_EQ(ma.epot, mb.epot);
  EXPECT_EQ(ma.z, m0.z);
  EXPECT_EQ(snapshot(rb, density, mb.pressure).mass, a.mass);
}

// A damaged configuration (a NaN spin, an infinite history entry, a zero radius, a
// meaningless history width) is refused on load naming the file and what is wrong, instead of
// being probed into null moduli.
TEST(SavedConfigurations, NonFiniteOrNonPositiveValuesAreRefusedOnLoad) {
  std::vector<double> density;
  auto sys = compressed_packing(density);
  const ConfigState good = snapshot(sys, density, sys.measure().pressure);
  const auto path = granular::testing::unique_temp_path("granular_config_damaged.h5").string();
  auto refused = [&](const ConfigState& c, const std::string& what) {
    write_config(path, c);
    try {
      read_config(path);
      ADD_FAILURE() << what << " was read";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
  };
  ConfigState c = good;
  c.w[3 * 7 + 1] = std::nan("");
  refused(c, "angular velocity of particle 7");
  c = good;
  c.history[5] = std::numeric_limits<double>::infinity();
  refused(c, "contact history entry 5");
  c = good;
  c.particles.radius[3] = 0.0;
  refused(c, "radius of particle 3");
  c = good;
  c.particles.x[2] = std::numeric_limits<double>::infinity();
  refused(c, "position of particle 2");
  write_config(path, good);
  EXPECT_NO_THROW(read_config(path));
  std::filesystem::remove(path);
}

TEST(SavedConfigurations, ProbingALoadedConfigurationGivesTheInRunModuliBitwise) {
  const auto root = granular::testing::unique_temp_path("granular_saved_config_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  opts.out_dir = (root / "prepare").string();
  run_elastic_moduli(scene(std::string(kPrepare) + kCommon, "prepare.toml"), opts);
  const std::string config = (root / "prepare" / "configs" / "phi_0.6800.h5").string();
  ASSERT_TRUE(std::filesystem::exists(config));

  opts.out_dir = (root / "restart").string();
  const std::string start =
      "scene = \"elastic_moduli\"\n[start]\nfrom = \"" + config + "\"\n" + kCommon;
  run_elastic_moduli(scene(start, "restart.toml"), opts);
  for (const char* name : {"K_star", "G_star", "M_star", "G_t_star", "eta_K", "z_corrected"}) {
    const auto a = column((root / "prepare").string(), name);
    const auto b = column((root / "restart").string(), name);
    ASSERT_EQ(a.size(), 1u);
    EXPECT_EQ(a, b) << name;
  }
  EXPECT_NE(column((root / "restart").string(), "G_t_star")[0], 0.0);  // springs take part

  // The history matters: the same configuration with its tangential springs dropped
  // probes differently, so the equality above is not automatic.
  ConfigState c = read_config(config);
  ASSERT_FALSE(c.pair_i.empty());
  const double with = column((root / "restart").string(), "G_star")[0];
  c.pair_i.clear(), c.pair_j.clear(), c.history.clear();
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.2, prm.damping.translational = 100, prm.damping.rotational = 20;
  const double inf = std::numeric_limits<double>::infinity();
  const Frictional model{
      LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, inf, inf), {}};
  auto sys = restart_system<DemSystem<Exec, Frictional>>(c, model, prm);
  const Moduli fresh = probe_moduli(sys, 3e-6, 200, 200);
  double dbar = 0;
  for (double a : c.particles.radius) dbar += 2 * a / c.size();
  EXPECT_NE(fresh.G * dbar / 1e5, with);
  std::filesystem::remove_all(root);
}

// Another tool's packing (start.from a state group, or a LAMMPS data file) is probed as the
// saved configuration it was written from, without that configuration's springs: the state
// group bit for bit (every position, velocity, spin, radius and the box read back exactly),
// the data file to round-off (SI text and back).
TEST(SavedConfigurations, AnotherToolsPackingIsProbedAsTheSavedConfigurationWithoutItsSprings) {
  const auto root = granular::testing::unique_temp_path("granular_external_packing_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  opts.out_dir = (root / "prepare").string();
  run_elastic_moduli(scene(std::string(kPrepare) + kCommon, "prepare.toml"), opts);
  ConfigState c = read_config((root / "prepare" / "configs" / "phi_0.6800.h5").string());
  ASSERT_FALSE(c.pair_i.empty());
  c.pair_i.clear(), c.pair_j.clear(), c.history.clear();
  const std::string springless = (root / "springless.h5").string();
  write_config(springless, c);
  const std::string state = (root / "state.h5").string();
  {
    H5Writer out(state);
    write_state(out, "/packing", particles_from<Exec>(c), c.box, 2000.0);
    out.commit();
  }
  HostParticles spun = c.particles;
  for (int i = 0; i < c.size(); ++i)
    spun.wx[i] = c.w[3 * i], spun.wy[i] = c.w[3 * i + 1], spun.wz[i] = c.w[3 * i + 2];
  const std::string data = (root / "packing.data").string();
  std::ofstream(data) << lammps_data_text(spun, c.box.lo, c.box.len);

  auto probe = [&](const std::string& name, const std::string& start) {
    opts.out_dir = (root / name).string();
    run_elastic_moduli(
        scene("scene = \"elastic_moduli\"\n[start]\n" + start + kCommon, name + ".toml"), opts);
    return opts.out_dir;
  };
  const std::string a = probe("saved", "from = \"" + springless + "\"\n");
  const std::string b =
      probe("state", "from = \"" + state + "\"\nfrom_group = \"/packing\"\ndensity = 2000.0\n");
  const std::string d = probe("data", "from = \"" + data + "\"\n");
  for (const char* name : {"K_star", "G_star", "M_star", "G_t_star", "z_corrected", "phi"}) {
    const auto saved = column(a, name), from_state = column(b, name), from_data = column(d, name);
    ASSERT_EQ(saved.size(), 1u) << name;
    EXPECT_EQ(saved, from_state) << name;
    ASSERT_EQ(from_data.size(), 1u) << name;
    EXPECT_NEAR(from_data[0], saved[0], 1e-9 * std::fabs(saved[0])) << name;
  }
  EXPECT_NE(column(b, "G_star")[0], 0.0);

  // An H5MD frame or a state group holds no density: without start.density it is refused,
  // naming the key.
  try {
    probe("no_density", "from = \"" + state + "\"\nfrom_group = \"/packing\"\n");
    ADD_FAILURE() << "a state group without start.density was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("start.density"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(root);
}

// A packing just compressed, far from equilibrium (its stress drifts on its own), saved as a
// state; make() restores it with a frictional model that never slides.
struct DriftingState {
  std::vector<double> density;
  DemSystem<Exec, Frictional> sys = compressed_packing(density);
  ConfigState c = snapshot(sys, density, sys.measure().pressure);
  Frictional model{LinearNormal::uniform(1e5, 1000),
                   CoulombTangential::uniform(8e4, 200, INFINITY, INFINITY),
                   {}};
  DemSystem<Exec, Frictional> make() const {
    return restart_system<DemSystem<Exec, Frictional>>(c, model, sys.params());
  }
};

TEST(SavedConfigurations, ReferenceRunRemovesRelaxationDriftFromProbedModuli) {
  const DriftingState state;
  auto make = [&] { return state.make(); };
  const Moduli a = probe_moduli_restarting(make, 2e-6, 200, 200);
  const Moduli b = probe_moduli_restarting(make, 1e-6, 100, 200);  // half amplitude, same rate
  // 100 particles just compressed still gain and lose contacts during a probe, so the
  // moduli keep a few per cent of amplitude dependence (the relaxed packings of the scenes
  // stay below 1 %); what the reference run removes is the drift, which is hundreds of per
  // cent of the volumetric moduli here.
  EXPECT_NEAR(b.K / a.K, 1.0, 0.05);
  EXPECT_NEAR(b.G / a.G, 1.0, 0.05);
  EXPECT_NEAR(b.M / a.M, 1.0, 0.05);
  // Without the reference run (in place, increments against the initial state) the drift
  // dominates: halving the amplitude changes the moduli by far more.
  auto s1 = make();
  auto s2 = make();
  const Moduli p = probe_moduli(s1, 2e-6, 200, 200);
  const Moduli q = probe_moduli(s2, 1e-6, 100, 200);
  EXPECT_GT(std::fabs(q.K / p.K - 1.0), 1.0);
  EXPECT_GT(std::fabs(q.M / p.M - 1.0), 1.0);
  EXPECT_LT(std::fabs(b.K / a.K - 1.0), 0.02 * std::fabs(q.K / p.K - 1.0));
}

TEST(SavedConfigurations, SharedReferenceRunGivesBitwiseTheModuliOfOwnReferenceRun) {
  // A drifting state, so the reference run matters: probes of the same length sharing it
  // must give exactly what probes running their own give, reversal residual included.
  const DriftingState state;
  auto make = [&] { return state.make(); };
  ReferenceRuns<DemSystem<Exec, Frictional>> shared;
  // The first probe keeps no second reference state; the next one, with a reversal, needs it.
  const Moduli a = probe_moduli_restarting(make, 2e-6, 200, 200, nullptr, 1, &shared);
  double rev_b = 0, rev_d = 0, own_rev_b = 0, own_rev_d = 0;
  const Moduli b = probe_moduli_restarting(make, 8e-6, 200, 200, &rev_b, 1, &shared);
  const Moduli d = probe_moduli_restarting(make, 8e-6, 100, 300, &rev_d, 1, &shared);
  const Moduli e = probe_moduli_restarting(make, 2e-6, 100, 100, nullptr, 1, &shared);
  EXPECT_EQ(shared.by_length.size(), 2u);  // lengths 400 (a, b, d) and 200 (e)
  const Moduli own_a = probe_moduli_restarting(make, 2e-6, 200, 200);
  const Moduli own_b = probe_moduli_restarting(make, 8e-6, 200, 200, &own_rev_b);
  const Moduli own_d = probe_moduli_restarting(make, 8e-6, 100, 300, &own_rev_d);
  const Moduli own_e = probe_moduli_restarting(make, 2e-6, 100, 100);
  const std::pair<Moduli, Moduli> pairs[] = {{a, own_a}, {b, own_b}, {d, own_d}, {e, own_e}};
  for (const auto& [x, y] : pairs) {
    EXPECT_EQ(x.K, y.K);
    EXPECT_EQ(x.G, y.G);
    EXPECT_EQ(x.M, y.M);
    EXPECT_EQ(x.eta_K, y.eta_K);
    EXPECT_EQ(x.eta_G, y.eta_G);
  }
  EXPECT_EQ(rev_b, own_rev_b);
  EXPECT_EQ(rev_d, own_rev_d);
  // Different probes of one length share the reference but not the result.
  EXPECT_NE(b.K, d.K);
}

TEST(SavedConfigurations, StudyStoppedAfterAVariantAndResumedEqualsUninterruptedStudyBitwise) {
  const auto root = granular::testing::unique_temp_path("granular_variant_resume_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  // Two preparation variants (friction 0 and 0.5), each with an amplitude sweep.
  std::string common = kCommon;
  const std::string relax = "relax_steps = 200\n";
  common.replace(common.find(relax), relax.size(), relax + "amplitudes = [1.0e-6, 1.0e-5]\n");
  const std::string text = std::string(kPrepare) + "mu = [0.0, 0.5]\n" + common;

  opts.out_dir = (root / "straight").string();
  run_elastic_moduli(scene(text, "study.toml"), opts);
  opts.out_dir = (root / "interrupted").string();
  run_elastic_moduli(scene(text + "stop_after_variants = 1\n", "study.toml"), opts);
  EXPECT_FALSE(std::filesystem::exists(root / "interrupted" / "results.h5"));
  EXPECT_FALSE(std::filesystem::exists(root / "interrupted" / "summary.json"));
  ASSERT_TRUE(std::filesystem::exists(root / "interrupted" / "variants"));
  // A fresh run does not overwrite the checkpoints of an unfinished study.
  EXPECT_THROW(run_elastic_moduli(scene(text, "study.toml"), opts), InputError);
  // A checkpoint is only taken up by the scene that wrote it.
  opts.resume = true;
  std::string other = text;
  other.replace(other.find("seed = 3"), 8, "seed = 4");
  EXPECT_THROW(run_elastic_moduli(scene(other, "study.toml"), opts), InputError);
  // The stopped study's folder moved elsewhere resumes there and lists its own
  // configurations, not the old folder's (the checkpoints store them relative to it).
  std::filesystem::rename(root / "interrupted", root / "moved");
  opts.out_dir = (root / "moved").string();
  run_elastic_moduli(scene(text, "study.toml"), opts);
  EXPECT_FALSE(std::filesystem::exists(root / "moved" / "variants"));  // superseded
  const std::string summary =
      granular::testing::read_text((root / "moved" / "summary.json").string());
  EXPECT_EQ(summary.find((root / "interrupted").string()), std::string::npos);
  EXPECT_NE(summary.find((root / "moved" / "configs").string()), std::string::npos);

  const H5Reader a((root / "straight" / "results.h5").string());
  const H5Reader b((root / "moved" / "results.h5").string());
  for (const char* name : {"/table/K_star", "/table/G_star", "/table/mu_preparation",
                           "/table/eta_G", "/preparation/phi", "/preparation/variant",
                           "/sweep/mu0.5_phi_0.6800/M_star", "/sweep/mu0_phi_0.6800/G_star"}) {
    ASSERT_TRUE(a.has(name)) << name;
    EXPECT_EQ(a.reals(name), b.reals(name)) << name;
  }
  EXPECT_EQ(a.reals("/table/mu_preparation"), (std::vector<double>{0.0, 0.5}));
  // The structure columns close: contact fractions sum to one, and the normal and
  // tangential parts of the pressure add up to the pressure.
  for (size_t r = 0; r < 2; ++r) {
    double sum = 0;
    for (const char* q : {"0", "1", "2", "3", "4", "5", "6_or_more"})
      sum += a.reals(std::string("/table/contact_fraction_") + q)[r];
    EXPECT_NEAR(sum, 1.0, 1e-12);
    EXPECT_NEAR(
        a.reals("/table/pressure_normal_star")[r] + a.reals("/table/pressure_tangential_star")[r],
        a.reals("/table/pressure_star")[r], 1e-9 * a.reals("/table/pressure_star")[r]);
    EXPECT_GT(a.reals("/table/fabric_xx")[r], 0.0);
  }
  std::filesystem::remove_all(root);
}

TEST(SavedConfigurations, StudyStoppedInsidePreparationStagesAndResumedTwiceEqualsUninterrupted) {
  const auto root = granular::testing::unique_temp_path("granular_stage_resume_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  const std::string text = std::string(kPrepare) + "mu = [0.0, 0.5]\n" + kCommon;

  opts.out_dir = (root / "straight").string();
  run_elastic_moduli(scene(text, "study.toml"), opts);
  // Stopped inside the first compression, then inside the second variant's, then finished.
  opts.out_dir = (root / "interrupted").string();
  run_elastic_moduli(scene(text + "stop_after_stages = 2\n", "study.toml"), opts);
  ASSERT_TRUE(std::filesystem::exists(root / "interrupted" / "variants" / "variant_0_mu0_stage"));
  opts.resume = true;
  run_elastic_moduli(scene(text + "stop_after_stages = 20\n", "study.toml"), opts);
  EXPECT_TRUE(std::filesystem::exists(root / "interrupted" / "variants" / "variant_0_mu0.index"));
  EXPECT_TRUE(std::filesystem::exists(root / "interrupted" / "variants" / "variant_1_mu0.5_stage"));
  EXPECT_FALSE(std::filesystem::exists(root / "interrupted" / "results.h5"));
  run_elastic_moduli(scene(text, "study.toml"), opts);

  const H5Reader a((root / "straight" / "results.h5").string());
  const H5Reader b((root / "interrupted" / "results.h5").string());
  for (const char* name : {"/table/K_star", "/table/G_star", "/table/M_star", "/table/z_corrected",
                           "/table/ekin_over_epot", "/preparation/phi", "/preparation/pressure"})
    EXPECT_EQ(a.reals(name), b.reals(name)) << name;
  EXPECT_EQ(a.reals("/table/K_star").size(), 2u);
  std::filesystem::remove_all(root);
}

// With an inertial-number rule the preparation's rate changes along the way; the save that
// follows a checkpoint reports its inertial number with the rate the protocol had reached,
// restored from the checkpoint (it used to restart from the nominal rate: 0.015 instead of
// 0.005). Stopped after every single stage and resumed each time.
TEST(SavedConfigurations, ResumedBeforeASaveReportsTheUninterruptedInertialNumber) {
  const auto root = granular::testing::unique_temp_path("granular_rate_resume_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  const std::string text =
      std::string(kPrepare) + "inertial_number = 1.0e-3\nmu = [0.5]\n" + kCommon;
  opts.out_dir = (root / "straight").string();
  run_elastic_moduli(scene(text, "study.toml"), opts);
  opts.out_dir = (root / "stepped").string();
  for (int run = 0; run < 200 && !std::filesystem::exists(root / "stepped" / "results.h5"); ++run) {
    run_elastic_moduli(scene(text + "stop_after_stages = 1\n", "study.toml"), opts);
    opts.resume = true;
  }
  const H5Reader a((root / "straight" / "results.h5").string());
  const H5Reader b((root / "stepped" / "results.h5").string());
  const auto I = a.reals("/table/inertial_number_preparation");
  ASSERT_EQ(I.size(), 1u);
  const auto rates = a.reals("/preparation/volumetric_strain_rate");
  EXPECT_LT(*std::min_element(rates.begin(), rates.end()), 0.9 * 2.0e-2)
      << "the rule lowers the rate: the check is not vacuous";
  for (const char* name : {"/table/inertial_number_preparation", "/table/K_star",
                           "/preparation/volumetric_strain_rate", "/preparation/phi"})
    EXPECT_EQ(a.reals(name), b.reals(name)) << name;
  std::filesystem::remove_all(root);
}

// On the loading branch the compression ends at the densest target. A checkpoint whose
// stage number lies at or past the last stage (left by a protocol with more stages, such as
// one that compressed on to phi_max) holds every saved configuration: the resumed run takes
// the preparation as complete and reruns nothing. A pointer that is not a stage number is an
// error, not a silent fresh start.
TEST(SavedConfigurations, CheckpointPastTheLastStageResumesAsCompletePreparation) {
  const auto root = granular::testing::unique_temp_path("granular_past_last_stage_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  std::string prep = kPrepare;
  const std::string targets = "targets = [0.68]\n";
  prep.replace(prep.find(targets), targets.size(), "targets = [0.66, 0.7]\nbranch = \"loading\"\n");
  const std::string text = prep + kCommon;

  opts.out_dir = (root / "straight").string();
  run_elastic_moduli(scene(text, "study.toml"), opts);
  const H5Reader a((root / "straight" / "results.h5").string());
  ASSERT_EQ(a.reals("/table/phi").size(), 2u);
  // The loading branch ends at the densest target, not at phi_max = 0.72.
  EXPECT_LT(a.reals("/preparation/phi").back(), 0.7 + 0.005);

  // Stop right after the stage that saves phi = 0.66: gas stages (0.47, 0.49, 0.5), relax,
  // strains 0.52 ... 0.66 (eight stages), save. Then relabel its checkpoint as a later stage's.
  opts.out_dir = (root / "interrupted").string();
  run_elastic_moduli(scene(text + "stop_after_stages = 13\n", "study.toml"), opts);
  const auto dir = root / "interrupted" / "variants";
  std::ifstream pointer(dir / "variant_0_stage");
  long k = -1;
  ASSERT_TRUE(pointer >> k);
  pointer.close();
  ASSERT_EQ(k, 12);
  for (const char* ext : {"_state.h5", ".h5", ".index"})
    std::filesystem::rename(dir / ("variant_0_stage12" + std::string(ext)),
                            dir / ("variant_0_stage40" + std::string(ext)));
  write_text_file((dir / "variant_0_stage").string(), "40\n");
  opts.resume = true;
  run_elastic_moduli(scene(text, "study.toml"), opts);
  EXPECT_FALSE(std::filesystem::exists(dir));  // its checkpoints are cleaned up
  const H5Reader b((root / "interrupted" / "results.h5").string());
  // Only the configuration the checkpoint held: no stage ran again.
  ASSERT_EQ(b.reals("/table/phi").size(), 1u);
  ASSERT_EQ(b.reals("/table/jammed")[0], 1.0);
  EXPECT_EQ(b.reals("/table/K_star")[0], a.reals("/table/K_star")[0]);
  EXPECT_EQ(b.reals("/table/G_star")[0], a.reals("/table/G_star")[0]);

  opts.out_dir = (root / "garbled").string();
  opts.resume = false;
  run_elastic_moduli(scene(text + "stop_after_stages = 3\n", "study.toml"), opts);
  write_text_file((root / "garbled" / "variants" / "variant_0_stage").string(), "x\n");
  opts.resume = true;
  EXPECT_THROW(run_elastic_moduli(scene(text, "study.toml"), opts), InputError);
  std::filesystem::remove_all(root);
}

// Relaxing a configuration below jamming: both energies decay and their ratio need not fall,
// so the relaxation asked to stop there returns at its first check once the contact network
// has come apart, while a jammed packing relaxes on under the same request.
TEST(SavedConfigurations, RelaxationStopsBelowJammingButNotAboveIt) {
  std::vector<double> density;
  auto jammed = compressed_packing(density);
  ASSERT_TRUE(is_jammed(jammed.measure()));
  long before = jammed.steps();
  relax(jammed, 1e-30, 2000, true);
  EXPECT_EQ(jammed.steps() - before, 2000);  // the flag does not cut a jammed packing short

  // Two copies of one loose state (Kokkos views would be shared by a copy of the system).
  auto loose = compressed_packing(density);
  auto unflagged = compressed_packing(density);
  strain_to_phi(loose, 0.50, 3e-2 / 3, 500, nullptr);
  strain_to_phi(unflagged, 0.50, 3e-2 / 3, 500, nullptr);
  const Measurements m = loose.measure();
  EXPECT_FALSE(is_jammed(m));
  before = loose.steps();
  relax(loose, 1e-30, 20000, true);
  EXPECT_EQ(loose.steps() - before, 500);
  // Without the flag the energy ratio alone does not end it.
  before = unflagged.steps();
  const double r = relax(unflagged, 1e-30, 2000, false);
  EXPECT_EQ(unflagged.steps() - before, 2000);
  EXPECT_GT(r, 1e-30);
}

// A few particles keeping the threshold number of contacts do not make a network: a state is
// jammed while at most half the particles are rattlers (jammed packings keep <= 15 %).
TEST(SavedConfigurations, JammedMeansMostParticlesKeepTheContactThreshold) {
  Measurements m;
  m.particles = 100, m.z_corrected = 4.2;
  m.rattlers = 15;
  EXPECT_TRUE(is_jammed(m));
  m.rattlers = 50;
  EXPECT_TRUE(is_jammed(m));
  m.rattlers = 51;
  EXPECT_FALSE(is_jammed(m));
  m.rattlers = 100, m.z_corrected = 0;
  EXPECT_FALSE(is_jammed(m));
}

// A study whose unloading branch reaches below jamming: the unjammed configuration is
// reported with zero moduli without being probed (no reversal residual), skips the halving
// probes, and the halving criterion is taken over the jammed configurations only.
TEST(SavedConfigurations, UnjammedConfigurationIsNotProbedAndLeftOutOfHalvingCheck) {
  const auto root = granular::testing::unique_temp_path("granular_unjammed_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  opts.out_dir = root.string();
  std::string text = std::string(kPrepare) + kCommon;
  text.replace(text.find("targets = [0.68]"), 16, "targets = [0.68, 0.52]");
  text.replace(text.find("[probe]"), 7, "[probe]\nhalving_check = true");
  text.replace(text.find("relax_max_steps = 2000"), 22, "relax_max_steps = 200000");
  // A faster gas stage: what is recorded after it must be the rate then applied, 2e-2.
  text.replace(text.find("targets ="), 9, "gas_strain_rate = 0.1\ntargets =");
  run_elastic_moduli(scene(text, "unjammed.toml"), opts);
  const std::string dir = root.string();
  {
    H5Reader h5(dir + "/results.h5");
    const auto phi_s = h5.reals("/preparation/phi"),
               rate_s = h5.reals("/preparation/volumetric_strain_rate"),
               I_s = h5.reals("/preparation/inertial_number"),
               P_s = h5.reals("/preparation/pressure");
    double dbar = 0;  // I = rate dbar sqrt(rho / P) on the series gives the mean diameter
    int after_gas = 0;
    // The gas stage's samples come first and end with the one that reaches phi_0 = 0.5
    // (it may overshoot by up to one step); every later sample is at the applied rate.
    bool gas = true;
    for (size_t i = 0; i < phi_s.size(); ++i) {
      EXPECT_DOUBLE_EQ(rate_s[i], gas ? 0.1 : 2e-2) << "sample " << i << " at phi " << phi_s[i];
      if (!gas && P_s[i] > 0) dbar = I_s[i] * std::sqrt(P_s[i] / 2000) / rate_s[i], ++after_gas;
      gas = gas && phi_s[i] < 0.5;
    }
    ASSERT_GT(after_gas, 0);
    EXPECT_GT(dbar, 1.0);
    EXPECT_LT(dbar, 3.0);
    // The table's I at the saved configuration: P = P* k_n / dbar from the relaxed state.
    const double P = column(dir, "pressure_star")[0] * column(dir, "kn_mean")[0] / dbar;
    EXPECT_NEAR(column(dir, "inertial_number_preparation")[0], 2e-2 * dbar * std::sqrt(2000 / P),
                1e-6 * column(dir, "inertial_number_preparation")[0]);
  }
  const auto jammed = column(dir, "jammed"), phi = column(dir, "phi"), K = column(dir, "K_star"),
             G = column(dir, "G_star"), rev = column(dir, "isotropic_reversal_residual"),
             half = column(dir, "halving_amplitude_rel_change_G");
  ASSERT_EQ(jammed.size(), 2u);
  EXPECT_NEAR(phi[0], 0.68, 1e-4);
  EXPECT_EQ(jammed[0], 1.0);
  EXPECT_GT(K[0], 0.0);
  EXPECT_TRUE(std::isfinite(half[0]));
  EXPECT_NEAR(phi[1], 0.52, 1e-4);
  EXPECT_EQ(jammed[1], 0.0);
  EXPECT_EQ(K[1], 0.0);
  EXPECT_EQ(G[1], 0.0);
  EXPECT_TRUE(std::isnan(rev[1]));   // not probed
  EXPECT_TRUE(std::isnan(half[1]));  // no halving probes
  std::ifstream f(root / "summary.json");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string summary = ss.str();
  EXPECT_NE(summary.find("\"unjammed_configurations_left_out\": 1"), std::string::npos)
      << summary.substr(summary.find("halving_check"), 300);
  std::filesystem::remove_all(root);
}

// The same packing with its axes relabelled (x, y, z) -> (z, x, y).
ConfigState axes_cycled(const ConfigState& c) {
  ConfigState r = c;
  HostParticles& p = r.particles;
  p.x = c.particles.y, p.y = c.particles.z, p.z = c.particles.x;
  p.vx = c.particles.vy, p.vy = c.particles.vz, p.vz = c.particles.vx;
  for (int d = 0; d < 3; ++d) {
    r.box.lo[d] = c.box.lo[(d + 1) % 3], r.box.len[d] = c.box.len[(d + 1) % 3];
    for (int i = 0; i < c.size(); ++i) r.w[3 * i + d] = c.w[3 * i + (d + 1) % 3];
    for (size_t k = 0; k < c.pair_i.size(); ++k)  // tangential springs are vectors
      r.history[3 * k + d] = c.history[3 * k + (d + 1) % 3];
  }
  return r;
}

// Shear in one plane and uniaxial strain along one axis see the anisotropy of a small
// packing; their means over the three planes and axes do not depend on how the axes are
// labelled, and for any linear response mean(M) = K + 4 mean(G)/3 exactly (the normal block
// of the stiffness: K = sum C_ab / 9, mean M = sum C_aa / 3, G_ab = (C_aa + C_bb - C_ab - C_ba)/4).
TEST(SavedConfigurations, ModuliAveragedOverOrientationsDoNotDependOnAxisLabels) {
  std::vector<double> density;
  auto sys = compressed_packing(density);
  relax(sys, 1e-8, 40000);
  const ConfigState c = snapshot(sys, density, sys.measure().pressure);
  ASSERT_EQ(c.history_width, 3);
  const ConfigState d = axes_cycled(c);
  const double inf = std::numeric_limits<double>::infinity();
  const Frictional model{
      LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, inf, inf), {}};
  using System = DemSystem<Exec, Frictional>;
  auto make_c = [&] { return restart_system<System>(c, model, sys.params()); };
  auto make_d = [&] { return restart_system<System>(d, model, sys.params()); };
  const Moduli one_c = probe_moduli_restarting(make_c, 2e-6, 200, 400, nullptr, 1);
  const Moduli one_d = probe_moduli_restarting(make_d, 2e-6, 200, 400, nullptr, 1);
  const Moduli all_c = probe_moduli_restarting(make_c, 2e-6, 200, 400, nullptr, 3);
  const Moduli all_d = probe_moduli_restarting(make_d, 2e-6, 200, 400, nullptr, 3);
  // One plane: the relabelled packing is sheared in what was its zx plane.
  EXPECT_GT(std::fabs(one_d.G / one_c.G - 1.0), 0.01);
  EXPECT_NEAR(all_d.K / all_c.K, 1.0, 1e-9);
  EXPECT_NEAR(all_d.G / all_c.G, 1.0, 1e-9);
  EXPECT_NEAR(all_d.M / all_c.M, 1.0, 1e-9);
  // This packing's response is anisotropic enough that one plane and one axis miss the
  // identity by several per cent; the means meet it up to the probe's nonlinearity.
  EXPECT_GT(std::fabs(one_c.M / (one_c.K + 4 * one_c.G / 3) - 1.0), 0.03);
  EXPECT_NEAR(all_c.M / (all_c.K + 4 * all_c.G / 3), 1.0, 0.01);
}

// Outputs checkpointed before the "jammed" column existed resume into tables that have it
// for every row (unjammed rows were those with Z = 0), so the columns stay aligned.
TEST(SavedConfigurations, CheckpointWithoutJammedColumnResumesAligned) {
  ModuliOutputs old_part, out;
  old_part.add_row("", {{"phi", 0.70}, {"z_corrected", 6.5}});
  old_part.add_row("", {{"phi", 0.66}, {"z_corrected", 0.0}});
  out.append(old_part);
  out.add_row("", {{"phi", 0.65}, {"z_corrected", 0.0}, {"jammed", 0.0}});
  ASSERT_EQ(out.table.at("jammed").size(), 3u);
  EXPECT_EQ(out.table.at("jammed"), (std::vector<double>{1.0, 0.0, 0.0}));
  EXPECT_EQ(out.table.at("phi").size(), 3u);
}

// The system-size scatter: mean and sample standard deviation over the seeds of each
// (friction, size, target), computed by hand here; unjammed rows carry no moduli and stay out.
TEST(SavedConfigurations, SizeScatterIsSampleStdOverSeedsOfJammedRowsOnly) {
  ModuliOutputs out;
  const auto row = [&](double n, double jammed, double K, double G) {
    out.add_row("", {{"mu_preparation", 0.5},
                     {"particles", n},
                     {"phi_target", 0.68},
                     {"jammed", jammed},
                     {"K_star", K},
                     {"G_star", G}});
  };
  row(1000, 1, 0.40, 0.30), row(1000, 1, 0.42, 0.36), row(1000, 1, 0.44, 0.33);
  row(1000, 0, 0.0, 0.0);  // unjammed seed
  row(8000, 1, 0.39, 0.31), row(8000, 1, 0.41, 0.33);
  const std::vector<SizeScatter> sc = size_scatter(out.table);
  ASSERT_EQ(sc.size(), 2u);
  EXPECT_EQ(sc[0].particles, 1000.0);
  EXPECT_EQ(sc[0].samples, 3);
  EXPECT_NEAR(sc[0].K_mean, 0.42, 1e-14);
  EXPECT_NEAR(sc[0].K_std, 0.02, 1e-14);  // sqrt((0.02^2 + 0 + 0.02^2) / 2)
  EXPECT_NEAR(sc[0].G_mean, 0.33, 1e-14);
  EXPECT_NEAR(sc[0].G_std, 0.03, 1e-14);  // sqrt((0.03^2 + 0.03^2 + 0) / 2)
  EXPECT_EQ(sc[1].particles, 8000.0);
  EXPECT_EQ(sc[1].samples, 2);
  EXPECT_NEAR(sc[1].K_std, std::sqrt(2 * 0.01 * 0.01), 1e-14);
  EXPECT_EQ(sc[0].mu, 0.5);
  // One seed per friction and target (a friction study): no scatter to report.
  ModuliOutputs single;
  for (double mu : {0.0, 0.5})
    single.add_row("", {{"mu_preparation", mu},
                        {"particles", 4096},
                        {"phi_target", 0.68},
                        {"jammed", 1},
                        {"K_star", 0.4},
                        {"G_star", 0.3}});
  EXPECT_TRUE(size_scatter(single.table).empty());
}

TEST(SavedConfigurations, CheckpointFingerprintIgnoresLaterKeysAtTheirOldDefaultOnly) {
  // A study checkpointed before probe.orientations existed used no such key; a newer run of
  // the same scene notes its default (1), which reproduces the old runs, and must resume.
  const std::map<std::string, std::string> before = {{"probe.amplitude", "1e-06"},
                                                     {"system.particles", "4096"}};
  auto with = [&](const std::string& k, const std::string& v) {
    auto m = before;
    m[k] = v;
    return m;
  };
  const std::string f = moduli_parameters_fingerprint(before);
  EXPECT_EQ(moduli_parameters_fingerprint(with("probe.orientations", "1")), f);
  EXPECT_EQ(moduli_parameters_fingerprint(with("run.stop_after_minutes", "30")), f);
  EXPECT_NE(moduli_parameters_fingerprint(with("probe.orientations", "3")), f);
  EXPECT_NE(moduli_parameters_fingerprint(with("probe.amplitude", "2e-06")), f);
  EXPECT_NE(moduli_parameters_fingerprint(with("probe.relax_steps", "100")), f);
}

// A time step per k_c variant (preparation.dt): each variant's preparation series is labelled
// with its own index (the jamming fit groups by it), and its probe takes the steps that span
// the duration run.dt's steps would (twice as many at half the step).
TEST(SavedConfigurations, PerVariantTimeStepLabelsEachSeriesAndKeepsTheProbeDuration) {
  const auto root = granular::testing::unique_temp_path("granular_variant_dt_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  std::string common = kCommon;
  const std::string linear = "normal = \"linear\"\nkn = 1.0e5\n";
  ASSERT_NE(common.find(linear), std::string::npos);
  common.replace(common.find(linear), linear.size(),
                 "normal = \"hysteretic\"\nk2 = 1.0e5\nk1 = 0.666e5\nkc = 1.0e5\n");
  const std::string text =
      std::string(kPrepare) + "kc = [0.0, 1.0e5]\ndt = [0.004, 0.002]\n" + common;
  opts.out_dir = root.string();
  run_elastic_moduli(scene(text, "study.toml"), opts);
  const H5Reader h((root / "results.h5").string());
  const std::vector<double> variant = h.reals("/preparation/variant");
  ASSERT_FALSE(variant.empty());
  for (double v : variant) EXPECT_TRUE(v == 0.0 || v == 1.0) << v;
  EXPECT_NE(std::count(variant.begin(), variant.end(), 0.0), 0);
  EXPECT_NE(std::count(variant.begin(), variant.end(), 1.0), 0);
  EXPECT_EQ(h.reals("/table/kc_preparation"), (std::vector<double>{0.0, 1.0e5}));
  EXPECT_EQ(h.reals("/table/probe_strain_steps"), (std::vector<double>{200.0, 400.0}));
  std::filesystem::remove_all(root);
}

// A study checkpoint's index closes with the count of its entries: a line lost (which used to
// resume with a column missing and phi_J null) or a file cut short is refused on resume.
TEST(SavedConfigurations, CheckpointIndexWithALostLineIsRefused) {
  const auto dir = granular::testing::unique_temp_path("granular_index_test");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "variants");
  const std::string parts = (dir / "variants").string();
  ModuliOutputs part;
  part.add_row("mu0", {{"K_star", 0.5}, {"G_star", 0.3}, {"phi", 0.68}});
  part.add_row("mu0", {{"K_star", 0.4}, {"G_star", 0.2}, {"phi", 0.66}});
  part.add_config((dir / "configs" / "phi_0.6800.h5").string());
  save_moduli_part(parts, "v", "fp", part);
  ModuliOutputs back;
  ASSERT_TRUE(load_moduli_part(parts, "v", "fp", back));
  EXPECT_EQ(back.table.at("K_star"), (std::vector<double>{0.5, 0.4}));
  EXPECT_EQ(back.config_paths, part.config_paths);

  const std::string index = parts + "/v.index";
  const std::string text = granular::testing::read_text(index);
  auto refused = [&](const std::string& damaged, const std::string& what) {
    std::ofstream(index) << damaged;
    ModuliOutputs p;
    try {
      load_moduli_part(parts, "v", "fp", p);
      ADD_FAILURE() << what << ": accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("damaged"), std::string::npos) << e.what();
    }
  };
  const size_t table_line = text.find("table G_star\n");
  ASSERT_NE(table_line, std::string::npos);
  refused(text.substr(0, table_line) + text.substr(table_line + 13), "a dropped table line");
  refused(text.substr(0, text.rfind("end ")), "no end line");
  std::filesystem::remove_all(dir);
}
