// Every shipped elastic_moduli scene file (quick and full variants) is valid: all keys are
// known, present where required and within range, so the hours-long full studies do not
// stop on a typo.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/scene_file.hpp"
#include "granular_config.hpp"
#include "scenarios/scene_registry.hpp"

using namespace granular;

TEST(ModuliSceneFiles, EveryShippedElasticModuliSceneReadsWithoutError) {
  int checked = 0;
  for (const auto& e :
       std::filesystem::directory_iterator(std::string(GRANULAR_SOURCE_DIR) + "/scenarios")) {
    if (e.path().extension() != ".toml") continue;
    const SceneFile s = SceneFile::load(e.path().string());
    if (s.text("scene") != "elastic_moduli") continue;
    EXPECT_NO_THROW(check_elastic_moduli(s)) << e.path();
    ++checked;
  }
  EXPECT_GE(checked, 10);  // five studies, quick and full
}
