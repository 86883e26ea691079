// Scene files: wrong, missing and unknown keys are errors that name the key and the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/io/scene_file.hpp"
#include "tests/test_support.hpp"

using granular::InputError;
using granular::SceneFile;

namespace {
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(SceneFile, UnknownKeyIsRejectedNamingKeyAndFile) {
  const auto s = SceneFile::parse("scene = \"x\"\n[contact]\nkn = 1.0\nkm = 2.0\n", "demo.toml");
  EXPECT_EQ(s.text("scene"), "x");
  EXPECT_DOUBLE_EQ(s.real("contact.kn"), 1.0);
  const std::string msg = error_of([&] { s.reject_unknown_keys(); });
  EXPECT_NE(msg.find("contact.km"), std::string::npos) << msg;
  EXPECT_NE(msg.find("demo.toml"), std::string::npos) << msg;
}

TEST(SceneFile, UnknownKeyNearAKnownOneSuggestsIt) {
  const auto s = SceneFile::parse("[contact]\nkn = 1.0\ngama_n = 2.0\n", "a.toml");
  s.real("contact.kn");
  s.real("contact.gamma_n", 0.0);  // read with its default: the file's spelling is unknown
  std::string msg = error_of([&] { s.reject_unknown_keys(); });
  EXPECT_NE(msg.find("unknown key 'contact.gama_n' (did you mean 'contact.gamma_n'?)"),
            std::string::npos)
      << msg;
  // Nothing near enough: no suggestion, the general advice.
  const auto t = SceneFile::parse("[contact]\nkn = 1.0\nstiffness = 2.0\n", "b.toml");
  t.real("contact.kn");
  msg = error_of([&] { t.reject_unknown_keys(); });
  EXPECT_EQ(msg.find("did you mean"), std::string::npos) << msg;
  EXPECT_NE(msg.find("misspelt, or not used by this scene"), std::string::npos) << msg;
}

TEST(SceneFile, MissingKeyNamesTheMisspellingInTheFile) {
  const auto s = SceneFile::parse("[contact]\nkn = 1.0\nshear_modulu = 29e3\n", "c.toml");
  s.real("contact.kn");
  const std::string msg = error_of([&] { s.real("contact.shear_modulus"); });
  EXPECT_NE(msg.find("'contact.shear_modulus' is missing"), std::string::npos) << msg;
  EXPECT_NE(msg.find("the file has 'contact.shear_modulu': misspelt?"), std::string::npos) << msg;
  // A key already read is not offered as the misspelling of another.
  const auto t = SceneFile::parse("[contact]\nkn = 1.0\n", "d.toml");
  t.real("contact.kn");
  EXPECT_EQ(error_of([&] { t.real("contact.kt"); }).find("misspelt?"), std::string::npos);
}

TEST(SceneFile, MissingAndMistypedKeysNameTheKey) {
  const auto s = SceneFile::parse("[run]\ndt = \"fast\"\nsteps = 1.5\n", "bad.toml");
  std::string msg = error_of([&] { s.real("run.skin"); });
  EXPECT_NE(msg.find("'run.skin' is missing"), std::string::npos) << msg;
  msg = error_of([&] { s.real("run.dt"); });
  EXPECT_NE(msg.find("'run.dt' must be a number"), std::string::npos) << msg;
  msg = error_of([&] { s.integer("run.steps"); });
  EXPECT_NE(msg.find("'run.steps' must be an integer"), std::string::npos) << msg;
  EXPECT_NE(msg.find("bad.toml"), std::string::npos) << msg;
}

TEST(SceneFile, DefaultsAreRecordedAndKnownKeysPass) {
  const auto s = SceneFile::parse("a = [1, 2.5]\n[t]\nb = true\n", "ok.toml");
  EXPECT_EQ(s.reals("a"), (std::vector<double>{1.0, 2.5}));
  EXPECT_TRUE(s.flag("t.b"));
  EXPECT_EQ(s.integer("t.c", 7), 7);
  EXPECT_NO_THROW(s.reject_unknown_keys());
  EXPECT_EQ(s.used().at("t.c"), "7");
}

TEST(SceneFile, SyntaxErrorReportsFileAndLine) {
  const std::string msg = error_of([] { SceneFile::parse("a = \n", "broken.toml"); });
  EXPECT_NE(msg.find("broken.toml"), std::string::npos) << msg;
}

// A copied scene keeps its inputs: relative paths are taken from the scene file's folder, not
// from the working directory, and a missing input is refused before the run, naming key, path
// and file.
TEST(SceneFile, RelativeInputPathsResolveFromTheSceneFilesFolder) {
  namespace fs = std::filesystem;
  const fs::path dir = granular::testing::temp_dir("scene_paths");
  fs::create_directories(dir / "inputs" / "study");
  std::ofstream(dir / "inputs" / "trace.csv") << "0,1\n";
  std::ofstream(dir / "scene.toml") << "trace = \"inputs/trace.csv\"\nstudy = \"inputs/study\"\n"
                                    << "absent = \"inputs/none.csv\"\nwrong = \"inputs/study\"\n";
  const fs::path cwd = fs::current_path();
  fs::current_path(fs::temp_directory_path());  // anywhere but the scene's folder
  const SceneFile s = SceneFile::load((dir / "scene.toml").string());
  EXPECT_EQ(s.input_path("trace"), (dir / "inputs" / "trace.csv").string());
  EXPECT_EQ(s.input_path("study", true), (dir / "inputs" / "study").string());
  EXPECT_EQ(s.optional_input_path("not_given"), "");
  std::string msg = error_of([&] { s.input_path("absent"); });
  EXPECT_NE(msg.find("'absent'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("inputs/none.csv"), std::string::npos) << msg;
  EXPECT_NE(msg.find("does not exist"), std::string::npos) << msg;
  EXPECT_NE(msg.find("scene.toml"), std::string::npos) << msg;
  msg = error_of([&] { s.input_path("wrong"); });
  EXPECT_NE(msg.find("a folder where a file is needed"), std::string::npos) << msg;
  msg = error_of([&] { s.input_path("trace", true); });
  EXPECT_NE(msg.find("a file where a folder is needed"), std::string::npos) << msg;
  // Absolute paths are taken as they are.
  const auto abs = SceneFile::parse("trace = \"" + (dir / "inputs" / "trace.csv").string() + "\"\n",
                                    "elsewhere.toml");
  EXPECT_EQ(abs.input_path("trace"), (dir / "inputs" / "trace.csv").string());
  fs::current_path(cwd);
  fs::remove_all(dir);
}
