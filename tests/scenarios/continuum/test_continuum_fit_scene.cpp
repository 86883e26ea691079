// The continuum_fit scene files: both shipped variants read without error, and a missing or
// unknown key stops the run before any work, naming the key and the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/io/scene_file.hpp"
#include "core/run/error.hpp"
#include "granular_config.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {
std::string read(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
// Checks a scene text as the CLI does (the `scene` key first) and returns the error message.
std::string error_of(const std::string& text, const std::string& name) {
  SceneFile s = SceneFile::parse(text, name);
  s.text("scene");
  try {
    check_continuum_fit(s);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ContinuumFitScene, ShippedSceneFilesReadWithoutError) {
  for (const char* name : {"continuum_fit.toml", "continuum_fit_quick.toml"}) {
    const std::string path = granular::testing::shipped_scene_path(name);
    EXPECT_EQ(error_of(read(path), path), "") << name;
  }
}

TEST(ContinuumFitScene, UnknownOrMissingKeyIsNamedWithTheFile) {
  const std::string path = granular::testing::shipped_scene_path("continuum_fit_quick.toml");
  const std::string text = read(path);
  // Named as if beside the shipped file, so its relative study paths resolve.
  const std::string dir = std::filesystem::path(path).parent_path().string() + "/";
  std::string typo = text;
  typo.insert(typo.find("[fit]\n") + 6, "z_minimum = 4.0\n");
  const std::string unknown = error_of(typo, dir + "typo.toml");
  EXPECT_NE(unknown.find("z_minimum"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("typo.toml"), std::string::npos) << unknown;
  std::string without = text;
  const size_t at = without.find("step = 4.0e-5");
  ASSERT_NE(at, std::string::npos);
  without.erase(at, without.find('\n', at) - at);
  const std::string missing = error_of(without, dir + "missing.toml");
  EXPECT_NE(missing.find("law.step"), std::string::npos) << missing;
  EXPECT_NE(missing.find("missing.toml"), std::string::npos) << missing;
}
