// The output context of a scene run (scenarios/common/scene_output.hpp): results.h5 exists only
// once finish() (or commit_results()) renamed it into place, a run that never finishes leaves
// no results.h5 and no summary.json, the summary lists the keys read before it was opened, and
// results that were committed take no more writes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"
#include "scenarios/common/scene_output.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::read_text;
namespace fs = std::filesystem;

namespace {

struct Folder {
  std::string dir, scene_path;
  explicit Folder(const std::string& name) : dir(granular::testing::temp_dir(name)) {
    fs::remove_all(dir);
    fs::create_directories(dir + "/out");
    scene_path = dir + "/scene.toml";
    std::ofstream(scene_path) << "scene = \"test\"\n[a]\nread_first = 1.5\nread_later = 2.5\n";
  }
  RunOptions options() const {
    RunOptions o;
    o.out_dir = dir + "/out";
    o.progress = false, o.charts = false;
    return o;
  }
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir + "/out"))
      names.push_back(e.path().filename().string());
    return names;
  }
};

}  // namespace

TEST(SceneOutput, RunThatNeverFinishesLeavesNoResultsNoSummaryAndNoPartialFile) {
  const Folder f("scene_output_unfinished");
  const SceneFile scene = SceneFile::load(f.scene_path);
  const RunOptions opts = f.options();
  {
    SceneOutput out(scene, opts, "test");
    out.h5().write("/x", std::vector<double>{1, 2, 3});
    out.summary()["value"] = 1.0;
  }  // a driver stopped at a checkpoint, or a failure, returns without finish()
  EXPECT_TRUE(f.files().empty()) << f.files().front();
}

TEST(SceneOutput, FinishRenamesTheResultsAndListsTheKeysReadBeforeTheSummaryOpened) {
  const Folder f("scene_output_finished");
  const SceneFile scene = SceneFile::load(f.scene_path);
  const RunOptions opts = f.options();
  SceneOutput out(scene, opts, "test");
  EXPECT_EQ(scene.real("a.read_first"), 1.5);
  out.h5().write("/x", std::vector<double>{1, 2, 3});
  EXPECT_FALSE(fs::exists(out.path("results.h5")));  // still under its hidden name
  out.summary()["value"] = 4.0;
  EXPECT_EQ(scene.real("a.read_later"), 2.5);
  out.finish();
  ASSERT_TRUE(fs::exists(out.path("results.h5")));
  EXPECT_EQ(H5Reader(out.path("results.h5")).reals("/x"), (std::vector<double>{1, 2, 3}));
  const std::string summary = read_text(out.path("summary.json"));
  EXPECT_NE(summary.find("\"scene\": \"test\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"a.read_first\""), std::string::npos) << summary;
  EXPECT_EQ(summary.find("\"a.read_later\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"value\": 4"), std::string::npos) << summary;
  EXPECT_EQ(f.files().size(), 2u);  // results.h5 and summary.json; no charts were asked for
}

TEST(SceneOutput, CommittedResultsTakeNoMoreWritesAndFinishDoesNotCommitThemTwice) {
  const Folder f("scene_output_committed");
  const SceneFile scene = SceneFile::load(f.scene_path);
  const RunOptions opts = f.options();
  SceneOutput out(scene, opts, "test");
  out.h5().write("/x", std::vector<double>{1});
  out.commit_results();  // before an XDMF sidecar that points into it
  EXPECT_TRUE(fs::exists(out.path("results.h5")));
  EXPECT_THROW(out.h5(), std::logic_error);
  EXPECT_NO_THROW(out.finish());
  EXPECT_TRUE(fs::exists(out.path("summary.json")));
}

TEST(SceneOutput, RunWithoutResultsWritesOnlyItsSummary) {
  const Folder f("scene_output_summary_only");
  const SceneFile scene = SceneFile::load(f.scene_path);
  const RunOptions opts = f.options();
  SceneOutput out(scene, opts, "test");
  out.finish();
  EXPECT_TRUE(fs::exists(out.path("summary.json")));
  EXPECT_FALSE(fs::exists(out.path("results.h5")));
}
