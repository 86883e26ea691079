// Bad values in shipped scene files are refused before anything runs or is allocated, with a
// message naming the key and the file: non-finite numbers, sizes the doubles or the neighbour
// grid cannot hold, particle counts beyond the machine's memory, meaningless densities and
// volume fractions. Each mutant here once crashed, hung, or allocated until the machine ran
// out of memory. `inf` stays legal where it means something (a rigid material).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "core/run/error.hpp"
#include "granular_config.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::shipped_scene;
using granular::testing::shipped_scene_path;
using granular::testing::temp_dir;

namespace {

// The scene text with the first line `key = ...` given a new value.
std::string mutate(const std::string& text, const std::string& key, const std::string& value) {
  const std::regex line("(^|\n)" + key + " *=[^\n]*");
  std::smatch m;
  EXPECT_TRUE(std::regex_search(text, m, line)) << key;
  return text.substr(0, m.position(0)) + m.str(1) + key + " = " + value +
         text.substr(m.position(0) + m.length(0));
}

struct Mutant {
  const char* key;       // the line to change (within its table)
  const char* value;     // its new value
  const char* full_key;  // what the message must name
};

// `name` is the scene file's name (its folder resolves the relative input paths inside it).
void expect_refused(const std::string& text, const Mutant& m,
                    void (*run)(const SceneFile&, const RunOptions&),
                    const std::string& name = "mutant.toml") {
  RunOptions opts;
  opts.out_dir = granular::testing::unique_temp_path("granular_guard").string();
  opts.progress = false, opts.charts = false;
  try {
    SceneFile scene = SceneFile::parse(mutate(text, m.key, m.value), name);
    (void)scene.text("scene");
    run(scene, opts);
    ADD_FAILURE() << m.full_key << " = " << m.value << " must be refused";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(m.full_key), std::string::npos) << m.value << ": " << what;
    EXPECT_NE(what.find(name), std::string::npos) << what;
  }
}

void check_moduli(const SceneFile& s, const RunOptions&) { check_elastic_moduli(s); }

}  // namespace

TEST(SceneInputGuards, IsotropicCompressionRefusesNonFiniteAndAbsurdValues) {
  const std::string text = shipped_scene("isotropic_compression.toml");
  const Mutant mutants[] = {
      {"diameter_max", "nan", "particles.diameter_max"},
      {"diameter_max", "inf", "particles.diameter_max"},
      {"diameter_max", "1e308", "particles.diameter_max"},
      {"count", "1000000000", "particles.count"},    // terabytes
      {"count", "100000000000", "particles.count"},  // past an int
      {"density", "-2000", "particles.density"},
      {"phi_start", "1e-320", "compression.phi_start"},
      {"dt", "nan", "run.dt"},
  };
  for (const Mutant& m : mutants) expect_refused(text, m, run_isotropic_compression);
}

TEST(SceneInputGuards, ElasticModuliRefusesNonFiniteAndAbsurdValues) {
  const std::string text = shipped_scene("moduli_linear_quick.toml");
  const Mutant mutants[] = {
      {"diameter_max", "1e308", "particles.diameter_max"},
      {"diameter_max", "inf", "particles.diameter_max"},
      {"phi_gas", "1e-320", "preparation.phi_gas"},
      {"count", "10000000000", "particles.count"},
      // A negative skin listed no pair and gave null moduli with exit 0.
      {"skin", "-0.2", "run.skin"},
  };
  for (const Mutant& m : mutants) expect_refused(text, m, check_moduli);
  // Keys the file leaves at their defaults, added to its [probe] table: a bound below the
  // probe's 20-step floor inverted std::clamp (K* inf, G* -inf); an orientation count beyond
  // an int was truncated by a cast.
  const size_t probe = text.find("[probe]\n");
  ASSERT_NE(probe, std::string::npos);
  const std::string with_keys = text.substr(0, probe + 8) +
                                "max_strain_steps = 200000\norientations = 1\n" +
                                text.substr(probe + 8);
  expect_refused(with_keys, {"max_strain_steps", "-1", "probe.max_strain_steps"}, check_moduli);
  expect_refused(with_keys, {"max_strain_steps", "19", "probe.max_strain_steps"}, check_moduli);
  expect_refused(with_keys, {"orientations", "4294967299", "probe.orientations"}, check_moduli);
}

// Counts above an int are refused naming the key, not truncated by a cast (the run used to
// go on with 100 steps per contact while summary.json recorded 4294967396).
TEST(SceneInputGuards, CountsBeyondAnIntAreRefusedNotTruncated) {
  const std::string text = shipped_scene("impact_glass_wall.toml");
  expect_refused(text, {"steps_per_contact", "4294967396", "impact.steps_per_contact"}, run_impact);
}

TEST(SceneInputGuards, InfinityIsLegalOnlyWhereItMeansRigid) {
  const std::string text = shipped_scene("confined_compression_quick.toml");
  // The shipped wall material is rigid (young_modulus = inf) and reads; nan there is refused,
  // and inf where a finite number is needed is refused too.
  expect_refused(text, {"young_modulus", "nan", "materials.hydrogel.young_modulus"},
                 run_confined_compression);
  expect_refused(text, {"wall_speed", "inf", "compression.wall_speed"}, run_confined_compression);
  expect_refused(text, {"diameter_spread", "1.5", "fill.diameter_spread"},
                 run_confined_compression);
}

TEST(SceneInputGuards, MixtureModuliRefusesBadFractionsPressuresAndMissingKeys) {
  const std::string text = shipped_scene("mixture_moduli_quick.toml");
  auto check = [](const SceneFile& s, const RunOptions&) { check_mixture_moduli(s); };
  const Mutant mutants[] = {
      {"soft_volume_fractions", "[0.2, 1.5]", "mixture.soft_volume_fractions"},
      {"soft_volume_fractions", "[-0.1]", "mixture.soft_volume_fractions"},
      {"soft_volume_fractions", "[]", "mixture.soft_volume_fractions"},
      {"pressures", "[]", "preparation.pressures"},
      {"pressures", "[0.0, 0.5]", "preparation.pressures"},
      {"pressures", "[0.5, -1.0]", "preparation.pressures"},
      {"pressures", "[0.5, 0.1]", "preparation.pressures"},                     // not ascending
      {"soft_volume_fraction", "0.3", "pair_rule_check.soft_volume_fraction"},  // not listed
      {"pair_rule", "\"arithmetic\"", "contact.pair_rule"},
      {"soft_material", "\"cork\"", "mixture.soft_material"},
      {"count", "1e12", "particles.count"},
  };
  for (const Mutant& m : mutants) expect_refused(text, m, check);
  // A missing key is named with its table.
  std::string missing = text;
  granular::testing::replace_once(missing, "tangential_stiffness = 150.0", "");
  expect_refused(missing, {"poisson", "0.5", "materials.rubber.tangential_stiffness"}, check);
}

// A list entry repeated in a list whose entries name outputs is refused before the run,
// naming the key; it used to run to the end and fail with "cannot create dataset".
TEST(SceneInputGuards, RepeatedListEntriesAreRefusedBeforeTheRun) {
  expect_refused(shipped_scene("confined_compression_quick.toml"),
                 {"stress_beta", "[1.0, 1.0]", "multicontact.stress_beta"},
                 run_confined_compression);
  expect_refused(shipped_scene("moduli_linear_quick.toml"),
                 {"targets", "[0.68, 0.68]", "preparation.targets"}, check_moduli);
}

// A chain's recording length sets the size of its energy profiles (samples x beads per block of
// realizations): refused naming time.t_max before anything is allocated, where it used to end in
// std::bad_alloc or take 8 GB first. Checked in check mode, so a missing guard cannot start the
// run.
TEST(SceneInputGuards, ChainRecordingBeyondMemoryIsRefusedNamingTMax) {
  const std::string text = shipped_scene("chain_impulse_quick.toml");
  auto check = [](const SceneFile& s, const RunOptions& o) {
    RunOptions c = o;
    c.check_only = true;
    run_chain_impulse(s, c);
  };
  expect_refused(text, {"t_max", "1e15", "time.t_max"}, check);  // beyond 1e9 samples
  expect_refused(text, {"t_max", "5e8", "time.t_max"}, check);   // profiles beyond memory
}

// `granular check` refuses a time step the run would refuse (the contact's t_c/50 guard), with
// the same message naming run.dt; it used to accept it and leave the refusal to the run.
TEST(SceneInputGuards, CheckModeAppliesTheRunsTimeStepGuard) {
  RunOptions opts;
  opts.check_only = true, opts.progress = false, opts.charts = false;
  opts.out_dir = granular::testing::unique_temp_path("granular_check_dt").string();
  // The shipped scene passes check; with `key = value` check refuses it with the run's
  // message (`advice`), naming the scene file.
  auto expect = [&](const char* file, void (*run)(const SceneFile&, const RunOptions&),
                    const char* key, const char* value, const char* advice) {
    const std::string text = shipped_scene(file);
    auto check = [&](const std::string& t, const std::string& name) {
      const SceneFile scene = SceneFile::parse(t, name);
      (void)scene.text("scene");  // read by the command line before it picks the driver
      run(scene, opts);
    };
    check(text, "ok.toml");
    try {
      check(mutate(text, key, value), "fast.toml");
      ADD_FAILURE() << file << ": " << key << " = " << value << " must be refused by check";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(advice), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("fast.toml"), std::string::npos) << e.what();
    }
  };
  expect("isotropic_compression.toml", run_isotropic_compression, "dt", "0.4", "set run.dt <=");
  EXPECT_FALSE(std::filesystem::exists(opts.out_dir));  // check writes nothing
  // The soft box: its settling system (particles, walls, gravity) is built in check mode too.
  expect("confined_compression_quick.toml", run_confined_compression, "time_step", "1e4",
         "compression.time_step");
  // The wave column: its servo's first system and walls.
  expect("wave_transmission_quick.toml", run_wave_transmission, "dt", "5.0", "set run.dt <=");
  // The moduli studies: each variant's gas with its preparation law; each mixture's gas.
  expect("moduli_linear_quick.toml", run_elastic_moduli, "dt", "0.4", "set run.dt <=");
  expect("mixture_moduli_quick.toml", run_mixture_moduli, "dt", "5.0", "set run.dt <=");
}

// Messages that used to name neither the key nor the file ("particle 0 has a non-positive
// radius or density", "gas volume fraction must be in (0, 0.45]", a deformation table's
// line without the key that names it) now name both, before anything runs.
TEST(SceneInputGuards, BadDiametersGasFractionAndHistoryTableAreRefusedNamingKeyAndFile) {
  expect_refused(shipped_scene("hysteretic_collision.toml"),
                 {"diameter_1", "0", "particles.diameter_1"}, run_hysteretic_collision);
  // The continuum fit resolves its study folders from the scene file's folder.
  const std::string here =
      (std::filesystem::path(shipped_scene_path("continuum_fit_quick.toml")).parent_path() /
       "mutant.toml")
          .string();
  auto check_fit = [](const SceneFile& s, const RunOptions&) { check_continuum_fit(s); };
  const std::string fit = shipped_scene("continuum_fit_quick.toml");
  expect_refused(fit, {"phi_gas", "0", "shear.phi_gas"}, check_fit, here);
  const std::string table = temp_dir("bad_history") + "/history.csv";
  {
    std::ofstream out(table);
    out << "time,F11,F12,F13,F21,F22,F23,F31,F32,F33\n0,1,0,0,0,1,0,0,0,1\n"
        << "0,1,0,0,0,1,0,0,0,1\n";  // time does not increase
  }
  const std::string quoted = "\"" + table + "\"";
  expect_refused(fit, {"file", quoted.c_str(), "history.file"}, check_fit, here);
}

// Two traces whose picked delay is not positive (trace2 is the nearer receiver): refused
// naming trace2.file and the scene, where the spectral ratio used to fail naming neither.
TEST(SceneInputGuards, SwappedTracesAreRefusedNamingTheTraceKey) {
  std::string text = shipped_scene("signal_analysis_traces.toml");
  const std::string one = "signal_example_trace1.csv", two = "signal_example_trace2.csv";
  const auto a = text.find(one), b = text.find(two);
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  text.replace(b, two.size(), one);
  text.replace(a, one.size(), two);
  const std::string name =
      (std::filesystem::path(shipped_scene_path("signal_analysis_traces.toml")).parent_path() /
       "swapped.toml")
          .string();
  RunOptions opts;
  opts.out_dir = granular::testing::unique_temp_path("granular_swapped").string();
  opts.progress = false, opts.charts = false;
  try {
    const SceneFile scene = SceneFile::parse(text, name);
    (void)scene.text("scene");  // read by the command line before it picks the driver
    run_signal_analysis(scene, opts);
    ADD_FAILURE() << "swapped traces must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("trace2.file"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(opts.out_dir + "/summary.json"));
  std::filesystem::remove_all(opts.out_dir);
}

// Multi-contact factors far beyond the source's 1-1.65 make the corrections outweigh the pair
// law the time-step guard sees: strain_gamma = 1e308 used to give NaN wall forces, exit 0.
TEST(SceneInputGuards, MultiContactFactorsBeyondTenAreRefusedNamingTheKey) {
  expect_refused(shipped_scene("confined_compression_quick.toml"),
                 {"strain_gamma", "[1.0, 1e308]", "multicontact.strain_gamma"},
                 run_confined_compression);
  expect_refused(shipped_scene("confined_compression_quick.toml"),
                 {"stress_beta", "[1.0, 11.0]", "multicontact.stress_beta"},
                 run_confined_compression);
}

// Found by the long real-run fuzz (seed 3): a phase of 2^31 us ran for years (the wave scene's
// probe, the mixture study's gas relaxation), the continuum fit's own gas check let
// shear.diameter_max = 1e308 through to a segmentation fault, and a confined box 2^31 mm wide
// ended in std::bad_alloc. Each is refused naming its key,
// in check mode, so a missing guard cannot start the run.
TEST(SceneInputGuards, PhasesOfYearsAndOverflowingGasDiametersAreRefused) {
  auto check_waves = [](const SceneFile& s, const RunOptions& o) {
    RunOptions c = o;
    c.check_only = true;
    run_wave_transmission(s, c);
  };
  const std::string waves = shipped_scene("wave_transmission_quick.toml");
  for (const char* key : {"hold_time", "ramp_time", "record_time", "final_relax_time"}) {
    const std::string table = std::string(key) == "record_time"        ? "pulse."
                              : std::string(key) == "final_relax_time" ? "preparation."
                                                                       : "probe.";
    expect_refused(waves, {key, "2147483648", (table + key).c_str()}, check_waves);
  }
  auto check_mixture = [](const SceneFile& s, const RunOptions&) { check_mixture_moduli(s); };
  expect_refused(shipped_scene("mixture_moduli_quick.toml"),
                 {"gas_relax_time", "2147483648", "preparation.gas_relax_time"}, check_mixture);
  auto check_continuum = [](const SceneFile& s, const RunOptions&) { check_continuum_fit(s); };
  expect_refused(shipped_scene("continuum_fit_quick.toml"),
                 {"diameter_max", "1e308", "shear.diameter_max"}, check_continuum,
                 shipped_scene_path("continuum_fit_quick.toml"));
  expect_refused(shipped_scene("continuum_fit_quick.toml"),
                 {"diameter_max", "1000.0", "shear.diameter_max"}, check_continuum,
                 shipped_scene_path("continuum_fit_quick.toml"));
  // A walled box 2^31 mm wide asked the neighbour grid for more cells than memory holds.
  auto check_confined = [](const SceneFile& s, const RunOptions& o) {
    RunOptions c = o;
    c.check_only = true;
    run_confined_compression(s, c);
  };
  expect_refused(shipped_scene("confined_compression_quick.toml"),
                 {"size", "[100.0, 2147483648.0, 110.0]", "box.size"}, check_confined);
}
