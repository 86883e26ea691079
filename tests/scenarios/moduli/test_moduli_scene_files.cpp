// Every shipped elastic_moduli scene file (quick and full variants) is valid: all keys are
// known, present where required and within range, so the hours-long full studies do not
// stop on a typo.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/io/scene_file.hpp"
#include "core/run/error.hpp"
#include "granular_config.hpp"
#include "scenarios/moduli/moduli_setup.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;

TEST(ModuliSceneFiles, EveryShippedElasticModuliSceneReadsWithoutError) {
  int checked = 0;
  for (const auto& path : granular::testing::shipped_scene_files()) {
    const SceneFile s = SceneFile::load(path.string());
    if (s.text("scene") != "elastic_moduli") continue;
    EXPECT_NO_THROW(check_elastic_moduli(s)) << path;
    ++checked;
  }
  EXPECT_GE(checked, 10);  // five studies, quick and full
}

// A value the driver cannot use stops the run before any work, naming the key and the file.
TEST(ModuliSceneFiles, UnsupportedProbeOrientationsNamesKeyAndFile) {
  const std::string path = granular::testing::shipped_scene_path("moduli_linear_quick.toml");
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  std::string text = ss.str();
  // As the CLI does: the `scene` key picks the driver before the driver reads the rest.
  auto scene = [](const std::string& t, const std::string& name) {
    SceneFile f = SceneFile::parse(t, name);
    f.text("scene");
    return f;
  };
  EXPECT_NO_THROW(check_elastic_moduli(scene(text, "good.toml")));
  text.replace(text.find("[probe]"), 7, "[probe]\norientations = 2");
  const SceneFile bad = scene(text, "bad_orientations.toml");
  try {
    check_elastic_moduli(bad);
    ADD_FAILURE() << "probe.orientations = 2 was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("probe.orientations"), std::string::npos) << what;
    EXPECT_NE(what.find("bad_orientations.toml"), std::string::npos) << what;
  }
}

// preparation.dt gives each k_c variant its own time step; every step count of the protocol is
// rescaled so that it spans the same physical time (the probe's strain rate and relaxation
// time, the relaxation cap), and a list that does not match preparation.kc is refused.
TEST(ModuliSceneFiles, PerVariantTimeStepKeepsEveryPhysicalDurationOfTheProtocol) {
  const std::string path = granular::testing::shipped_scene_path("cohesion_list.toml");
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  auto setup = [](const std::string& t, const std::string& name) {
    SceneFile f = SceneFile::parse(t, name);
    f.text("scene");
    return moduli_study::read_setup(f);
  };
  const moduli_study::Setup s = setup(text, "cohesion_list.toml");
  ASSERT_EQ(s.variants.size(), 4u);
  for (const moduli_study::PrepVariant& v : s.variants) {
    ASSERT_FALSE(std::isnan(v.dt));
    const moduli_study::Setup r = moduli_study::for_variant(s, v);
    EXPECT_EQ(r.params.dt, v.dt);
    const double base = s.params.dt;
    // Durations equal to within one step's rounding.
    EXPECT_NEAR(r.strain_steps * r.params.dt, s.strain_steps * base, 0.5 * r.params.dt);
    EXPECT_NEAR(r.probe_relax * r.params.dt, s.probe_relax * base, 0.5 * r.params.dt);
    EXPECT_NEAR(static_cast<double>(r.relax_max) * r.params.dt,
                static_cast<double>(s.relax_max) * base, 0.5 * r.params.dt);
    // Everything else is the study's.
    EXPECT_EQ(r.amplitude, s.amplitude);
    EXPECT_EQ(r.rate, s.rate);
    EXPECT_EQ(r.targets, s.targets);
  }
  // The variant of k_c = 10 k2 keeps the reference step: its counts are unchanged.
  const moduli_study::Setup stiff = moduli_study::for_variant(s, s.variants.back());
  EXPECT_EQ(stiff.strain_steps, s.strain_steps);
  EXPECT_EQ(stiff.relax_max, s.relax_max);

  std::string bad = text;
  const size_t at = bad.find("dt = [0.0037, 0.0037, 0.0037, 0.0012]");
  ASSERT_NE(at, std::string::npos);
  bad.replace(at, 37, "dt = [0.0037, 0.0012]");
  try {
    setup(bad, "short_dt_list.toml");
    ADD_FAILURE() << "a preparation.dt list shorter than preparation.kc was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("preparation.dt"), std::string::npos) << what;
    EXPECT_NE(what.find("short_dt_list.toml"), std::string::npos) << what;
  }
}
