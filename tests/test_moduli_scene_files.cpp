// Every shipped elastic_moduli scene file (quick and full variants) is valid: all keys are
// known, present where required and within range, so the hours-long full studies do not
// stop on a typo.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/scene_file.hpp"
#include "granular_config.hpp"
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
