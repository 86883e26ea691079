// Scene-level checks of the signal and wave scenes: the shipped laboratory-style example
// (two constant-Q wavelets, Q = 20, delays 5 and 15) analysed end to end from its CSV files
// recovers Q and the delay; bad keys stop the runs with an InputError naming key and file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "granular_config.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/scene_registry.hpp"
#include "scenarios/waves/skeleton.hpp"
#include "scenarios/waves/wave_setup.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::replace_once;
using granular::testing::shipped_scene;
using granular::testing::temp_dir;

namespace {
std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
// The number after "key": in a JSON text, searched from `after`.
double json_number(const std::string& json, const std::string& key, const std::string& after) {
  const auto from = json.find(after);
  const auto at = json.find("\"" + key + "\":", from);
  EXPECT_NE(at, std::string::npos) << key;
  return std::stod(json.substr(at + key.size() + 3));
}
}  // namespace

TEST(SignalAnalysisScene, ShippedExampleTracesGiveTheirQAndDelay) {
  std::string text = shipped_scene("signal_analysis_traces.toml");
  const std::string src = std::string(GRANULAR_SOURCE_DIR) + "/scenarios/waves/";
  replace_once(text, "\"signal_example_trace1.csv\"", "\"" + src + "signal_example_trace1.csv\"");
  replace_once(text, "\"signal_example_trace2.csv\"", "\"" + src + "signal_example_trace2.csv\"");
  RunOptions opts;
  opts.out_dir = temp_dir("signal_traces");
  opts.progress = false, opts.charts = false;
  const SceneFile scene = SceneFile::parse(text, "signal_analysis_traces.toml");
  (void)scene.text("scene");  // read by the command line before it picks the driver
  run_signal_analysis(scene, opts);
  const std::string js = slurp(opts.out_dir + "/summary.json");
  // Noise 1e-4 of the source peak: Q within 1 % and the peak-to-peak delay within a
  // tenth of a source period of the true delay 10 (dispersion shifts the peaks by less).
  EXPECT_NEAR(json_number(js, "Q", "\"spectral_ratio\""), 20.0, 0.2);
  EXPECT_NEAR(json_number(js, "first_peak", "\"travel_time_differences\""), 10.0, 0.1);
  std::filesystem::remove_all(opts.out_dir);
}

TEST(SignalAnalysisScene, UnknownWindowNamesKeyAndFile) {
  std::string text = shipped_scene("signal_analysis_synthetic.toml");
  replace_once(text, "window = \"span\"", "window = \"hann\"");
  RunOptions opts;
  opts.out_dir = temp_dir("signal_bad");
  opts.progress = false, opts.charts = false;
  try {
    run_signal_analysis(SceneFile::parse(text, "bad_signal.toml"), opts);
    FAIL() << "an unknown window must stop the run";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("analysis.spectrum.window"), std::string::npos) << what;
    EXPECT_NE(what.find("bad_signal.toml"), std::string::npos) << what;
  }
  EXPECT_FALSE(std::filesystem::exists(opts.out_dir + "/summary.json"));
}

TEST(WaveTransmissionScene, BadVolumeFractionsAndMaterialsNameKeyAndFile) {
  const std::pair<std::string, std::string> cases[] = {
      {"volume_fractions = [1.0]", "volume_fractions = [0.7]"},
      {"materials = \"glass\"", "materials = \"brass\""},
      {"pair_rule = \"harmonic\"", "pair_rule = \"geometric\""},
  };
  const char* keys[] = {"mixture.volume_fractions", "mixture.materials", "contact.pair_rule"};
  for (int k = 0; k < 3; ++k) {
    std::string text = shipped_scene("wave_transmission_quick.toml");
    replace_once(text, cases[k].first, cases[k].second);
    RunOptions opts;
    opts.out_dir = temp_dir("wave_bad");
    opts.progress = false, opts.charts = false;
    try {
      run_wave_transmission(SceneFile::parse(text, "bad_wave.toml"), opts);
      ADD_FAILURE() << keys[k] << ": bad input must stop the run";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(keys[k]), std::string::npos) << what;
      EXPECT_NE(what.find("bad_wave.toml"), std::string::npos) << what;
    }
    EXPECT_FALSE(std::filesystem::exists(opts.out_dir + "/summary.json"));
  }
}

TEST(WaveSkeleton, RattlersArePeeledRoundAfterRoundWithWallsAsContacts) {
  // Column x in [0, 10] between the walls, periodic along y and z (length 10).
  // A (x = 0.9) touches the source wall and B; B (x = 2.8) touches A and C; C (x = 4.7) touches B
  // only; D touches E across the periodic y boundary, E touches D only; F touches nothing.
  ConfigState c;
  c.box.len[0] = c.box.len[1] = c.box.len[2] = 10;
  c.box.periodic[1] = c.box.periodic[2] = true;
  const double rows[6][4] = {{0.9, 2.0, 2.0, 1.0}, {2.8, 2.0, 2.0, 1.0}, {4.7, 2.0, 2.0, 1.0},
                             {3.0, 0.2, 7.0, 0.5}, {3.0, 9.5, 7.0, 0.5}, {3.0, 5.0, 5.0, 0.3}};
  c.particles.resize(6);
  for (int i = 0; i < 6; ++i) {
    c.particles.x[i] = rows[i][0], c.particles.y[i] = rows[i][1], c.particles.z[i] = rows[i][2];
    c.particles.radius[i] = rows[i][3];
    c.mass.push_back(std::pow(rows[i][3], 3));
  }
  const double total = 3 + 2 * 0.125 + 0.027;
  // Below 2 contacts: F (none), then C, D, E (one each); C's removal leaves B with one (A), so B
  // goes next, then A (the wall alone): everything is peeled.
  EXPECT_NEAR(rattler_mass_fraction(c, 0.0, 10.0, 2), 1.0, 1e-15);
  // With a receiver wall at x = 5.5, C touches it: A-B-C bridges the walls and stays.
  EXPECT_NEAR(rattler_mass_fraction(c, 0.0, 5.5, 2), (2 * 0.125 + 0.027) / total, 1e-15);
  // Nothing is a rattler below one contact except F.
  EXPECT_NEAR(rattler_mass_fraction(c, 0.0, 5.5, 1), 0.027 / total, 1e-15);
}

// A target the servo does not reach within preparation.max_time (here 3000 us, shorter than
// the gas compression alone) is left out: no probe, no pulse, no group in results.h5, NaN in
// the tables, and summary.json lists it with the servo's last held states; the run ends.
// With preparation.unconverged = "stop" the run stops instead, naming the key to raise.
TEST(WaveTransmissionScene, TargetTheServoDoesNotReachIsListedAndNotAnalysed) {
  std::string text = shipped_scene("wave_transmission_quick.toml");
  replace_once(text, "pressures = [0.05, 0.2, 0.5]", "pressures = [0.05]");
  replace_once(text, "max_time = 200000.0", "max_time = 3000.0");
  RunOptions opts;
  opts.out_dir = temp_dir("wave_unconverged");
  opts.progress = false, opts.charts = false;
  auto scene = [&] {  // as the command line does: `scene` picks the driver
    SceneFile s = SceneFile::parse(text, "short_servo.toml");
    (void)s.text("scene");
    return s;
  };
  run_wave_transmission(scene(), opts);
  const std::string js = slurp(opts.out_dir + "/summary.json");
  const auto listed = js.find("\"unconverged_states\"");
  ASSERT_NE(listed, std::string::npos) << js;
  EXPECT_DOUBLE_EQ(json_number(js, "target_sigma_xx", "\"unconverged_states\""), 0.05);
  EXPECT_NE(js.find("preparation.max_time", listed), std::string::npos);
  EXPECT_NE(js.find("\"servo_converged\": false"), std::string::npos) << js;
  {
    const H5Reader h5(opts.out_dir + "/results.h5");
    EXPECT_FALSE(h5.has("/pressure_0"));
    const auto vp = h5.reals("/table/V_p_first_peak");
    ASSERT_EQ(vp.size(), 1u);
    EXPECT_TRUE(std::isnan(vp[0]));
    EXPECT_TRUE(std::isnan(h5.reals("/table/M_probe")[0]));
  }
  std::filesystem::remove_all(opts.out_dir);

  replace_once(text, "max_time = 3000.0", "max_time = 3000.0\nunconverged = \"stop\"");
  opts.out_dir = temp_dir("wave_unconverged_stop");
  try {
    run_wave_transmission(scene(), opts);
    ADD_FAILURE() << "preparation.unconverged = \"stop\" must stop the run";
  } catch (const PhysicsError& e) {
    EXPECT_NE(std::string(e.what()).find("preparation.max_time"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(opts.out_dir + "/summary.json"));
  std::filesystem::remove_all(opts.out_dir);
}

// column.from: another tool's packing (here a periodic gas written as a state group, species 0
// and 1) fills the column: species k becomes the k-th material of mixture.materials with its
// density, the walls stand at the particles' extent along x (no particle starts in a wall),
// y and z keep the file's periodic width, and the volume fractions, mean diameter and length
// come from the file. A run from it prepares exactly the file's particles. Keys that would
// draw the column, and a species without a material, are refused naming the key.
TEST(WaveTransmissionScene, PackingFileFillsTheColumnBetweenWallsAtItsExtent) {
  GasSpec gas;
  gas.count = 200, gas.diameter_min = 3.8, gas.diameter_max = 4.2, gas.phi = 0.3, gas.seed = 5;
  PeriodicBox file_box;
  HostParticles h = random_gas(gas, file_box);
  for (int i = 0; i < h.size(); ++i) h.species[i] = i % 3 == 0 ? 1 : 0;  // a third rubber
  const std::string dir = temp_dir("wave_packing");
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/gas.h5";
  {
    H5Writer w(file);
    write_state(w, "/final_state", Particles<Kokkos::DefaultExecutionSpace>::from_host(h), file_box,
                1.0);
    w.commit();
  }
  std::string text = shipped_scene("wave_transmission_mixture_quick.toml");
  replace_once(text, "volume_fractions = [0.8, 0.2]\n", "");
  replace_once(text,
               "length = 16.0\nwidth = 4.0\ndiameter = 4.0\nspread = 0.05\n"
               "gas_volume_fraction = 0.35\nseed = 1\n",
               "from = \"" + file + "\"\n");
  replace_once(text, "max_time = 200000.0", "max_time = 3000.0");
  const WaveSetup w = read_wave_setup(SceneFile::parse(text, "from_file.toml"));
  ASSERT_TRUE(w.from.has_value());
  const HostParticles& c = *w.from;
  ASSERT_EQ(c.size(), h.size());
  double lo = INFINITY, hi = -INFINITY, v = 0, v_rubber = 0, dsum = 0;
  const int glass = w.mats.slot.at("glass"), rubber = w.mats.slot.at("rubber");
  for (int i = 0; i < c.size(); ++i) {
    const double r = c.radius[i];
    lo = std::min(lo, c.x[i] - r), hi = std::max(hi, c.x[i] + r);
    EXPECT_EQ(c.species[i], h.species[i] == 1 ? rubber : glass) << i;
    EXPECT_EQ(c.density[i], h.species[i] == 1 ? 1270.0 : 2540.0) << i;
    v += r * r * r, dsum += 2 * r;
    if (h.species[i] == 1) v_rubber += r * r * r;
  }
  EXPECT_NEAR(lo, 0.0, 1e-12);
  EXPECT_NEAR(hi, w.from_box.len[0], 1e-12);
  EXPECT_FALSE(w.from_box.periodic[0]);
  EXPECT_EQ(w.from_box.len[1], file_box.len[1]);
  EXPECT_EQ(w.from_box.len[2], file_box.len[2]);
  ASSERT_EQ(w.fractions.size(), 2u);
  EXPECT_NEAR(w.fractions[1], v_rubber / v, 1e-14);
  EXPECT_NEAR(w.fractions[0] + w.fractions[1], 1.0, 1e-14);
  EXPECT_NEAR(w.diameter, dsum / c.size(), 1e-12);

  // A short run (the servo stops at max_time; the state is listed, not analysed): the file's
  // particles and mixture are the run's.
  RunOptions opts;
  opts.out_dir = temp_dir("wave_from_file");
  opts.progress = false, opts.charts = false;
  SceneFile scene = SceneFile::parse(text, "from_file.toml");
  (void)scene.text("scene");
  run_wave_transmission(scene, opts);
  const std::string js = slurp(opts.out_dir + "/summary.json");
  EXPECT_EQ(json_number(js, "particles", ""), 200.0);
  EXPECT_NEAR(json_number(js, "rubber", "\"volume_fractions_of_file\""), v_rubber / v, 1e-12);
  std::filesystem::remove_all(opts.out_dir);

  const std::pair<std::string, std::string> bad[] = {
      {"materials = \"glass\"", "mixture.materials"},  // the rubber beads have no material
      {"from = \"" + file + "\"\nseed = 2", "column.seed"}};
  const std::string firsts[] = {"materials = \"glass, rubber\"", "from = \"" + file + "\""};
  for (int k = 0; k < 2; ++k) {
    std::string t = text;
    replace_once(t, firsts[k], bad[k].first);
    try {
      read_wave_setup(SceneFile::parse(t, "bad_from.toml"));
      ADD_FAILURE() << bad[k].second << ": must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad[k].second), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}
