// Checkpoints: a compression interrupted after a checkpoint and continued with --resume
// ends in exactly the state of the uninterrupted run, and the interrupted run leaves no
// results file that looks finished.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::shipped_scene;
using granular::testing::temp_dir;

namespace {
const std::string kScene = granular::testing::small_isotropic_scene();

// As the CLI does: the `scene` key picks the driver before the driver reads the rest.
SceneFile scene(const std::string& text, const std::string& name) {
  SceneFile s = SceneFile::parse(text, name);
  EXPECT_EQ(s.text("scene"), "isotropic_compression");
  return s;
}

std::vector<double> final_positions(const std::string& dir) {
  return H5Reader(dir + "/results.h5").reals("/final_state/position");
}
}  // namespace

TEST(CheckpointResume, InterruptedAndResumedRunEqualsUninterruptedRunBitwise) {
  const auto root = granular::testing::unique_temp_path("granular_resume_test");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;

  opts.out_dir = (root / "straight").string();
  run_isotropic_compression(scene(kScene, "straight.toml"), opts);

  opts.out_dir = (root / "interrupted").string();
  const std::string interrupted = kScene + "stop_after = 3000\n";
  run_isotropic_compression(scene(interrupted, "interrupted.toml"), opts);
  EXPECT_FALSE(std::filesystem::exists(root / "interrupted" / "results.h5"));
  ASSERT_TRUE(std::filesystem::exists(root / "interrupted" / "checkpoint.h5"));
  opts.resume = true;
  run_isotropic_compression(scene(kScene, "interrupted.toml"), opts);

  const auto a = final_positions((root / "straight").string());
  const auto b = final_positions((root / "interrupted").string());
  ASSERT_EQ(a.size(), 900u);
  EXPECT_EQ(a, b);
  // The time series is complete too: same samples in the same order.
  EXPECT_EQ(H5Reader((root / "straight" / "results.h5").string()).reals("/series/pressure"),
            H5Reader((root / "interrupted" / "results.h5").string()).reals("/series/pressure"));
  EXPECT_FALSE(std::filesystem::exists(root / "interrupted" / "checkpoint.h5"));  // superseded
  std::filesystem::remove_all(root);
}

TEST(CheckpointResume, CheckpointIntervalLeavesTheTrajectoryBitwiseUnchanged) {
  // Writing a checkpoint must not touch the state (no neighbour rebuild, no force refresh):
  // runs that checkpoint every 2000, 700 or 333 steps, or never within the run, end alike.
  const auto root = granular::testing::unique_temp_path("granular_checkpoint_interval");
  std::filesystem::remove_all(root);
  RunOptions opts;
  opts.progress = false, opts.charts = false;
  std::vector<std::vector<double>> finals;
  std::vector<double> builds;
  for (const char* every : {"2000", "700", "333", "100000000"}) {
    std::string text = kScene;
    const std::string from = "checkpoint_every = 2000";
    text.replace(text.find(from), from.size(), std::string("checkpoint_every = ") + every);
    opts.out_dir = (root / every).string();
    run_isotropic_compression(scene(text, std::string("every_") + every + ".toml"), opts);
    finals.push_back(final_positions(opts.out_dir));
    builds.push_back(
        H5Reader(opts.out_dir + "/results.h5").reals("/series/neighbor_builds").back());
  }
  for (size_t k = 1; k < finals.size(); ++k) {
    EXPECT_EQ(finals[k], finals[0]) << k;
    EXPECT_EQ(builds[k], builds[0]) << k;
  }
  std::filesystem::remove_all(root);
}

namespace {
// A run stopped after its checkpoint at step 3000 in <root>/run; returns the checkpoint.
std::string stopped_run(const std::filesystem::path& root, RunOptions& opts) {
  std::filesystem::remove_all(root);
  opts.progress = false, opts.charts = false;
  opts.out_dir = (root / "run").string();
  run_isotropic_compression(scene(kScene + "stop_after = 3000\n", "a.toml"), opts);
  const std::string checkpoint = (root / "run" / "checkpoint.h5").string();
  EXPECT_TRUE(std::filesystem::exists(checkpoint));
  return checkpoint;
}

// --resume must be refused with an InputError naming the checkpoint and `detail`.
void expect_resume_refused(RunOptions opts, const std::string& checkpoint,
                           const std::string& detail) {
  opts.resume = true;
  try {
    run_isotropic_compression(scene(kScene, "a.toml"), opts);
    ADD_FAILURE() << "a damaged checkpoint was resumed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(checkpoint), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(detail), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(opts.out_dir + "/results.h5"));
}
}  // namespace

// A checkpoint holds the particles once, in its restart group: the snapshot copy (/state)
// it used to hold beside it doubled its size and was read only to build a system that the
// restart then overwrote.
TEST(CheckpointResume, CheckpointHoldsTheParticlesOnceInItsRestartGroup) {
  const auto root = granular::testing::unique_temp_path("granular_checkpoint_once");
  RunOptions opts;
  const std::string checkpoint = stopped_run(root, opts);
  {
    const H5Reader in(checkpoint);
    EXPECT_FALSE(in.has("/state"));
    EXPECT_EQ(in.reals("/restart/particles/x").size(), 900u);
    EXPECT_TRUE(in.has("/series/pressure"));
  }
  std::filesystem::remove_all(root);
}

// Six garbled bytes in a checkpoint used to resume the run with other results, exit 0: the
// file's checksum now refuses it, naming the file, before any state is taken from it.
TEST(CheckpointResume, CheckpointWithGarbledBytesIsRefusedNamingTheFile) {
  const auto root = granular::testing::unique_temp_path("granular_garbled_checkpoint");
  RunOptions opts;
  const std::string checkpoint = stopped_run(root, opts);
  {
    std::fstream f(checkpoint, std::ios::in | std::ios::out | std::ios::binary);
    const auto size = static_cast<std::streamoff>(std::filesystem::file_size(checkpoint));
    for (int k = 1; k <= 6; ++k) {
      f.seekp(size * k / 7);
      f.put('\x7f');
    }
  }
  expect_resume_refused(opts, checkpoint, "checksum");
  std::filesystem::remove_all(root);
}

// A checkpoint whose restart datasets have another size (here a file without the checksum,
// as older versions and other tools write) is refused naming the checkpoint, where the message
// used to name only "restart group /restart".
TEST(CheckpointResume, RestartDatasetOfAnotherSizeIsRefusedNamingTheCheckpoint) {
  const auto root = granular::testing::unique_temp_path("granular_restart_size");
  RunOptions opts;
  const std::string checkpoint = stopped_run(root, opts);
  {
    const hid_t file = H5Fopen(checkpoint.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    ASSERT_GE(H5Ldelete(file, "/restart/scalars", H5P_DEFAULT), 0);
    const hsize_t dims[1] = {3};
    const double three[3] = {0, 0, 0};
    const hid_t space = H5Screate_simple(1, dims, nullptr);
    const hid_t set = H5Dcreate2(file, "/restart/scalars", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT,
                                 H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(set, 0);
    H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, three);
    H5Dclose(set), H5Sclose(space), H5Fclose(file);
    std::fstream f(checkpoint, std::ios::in | std::ios::out | std::ios::binary);
    f.write(std::string(512, '\0').data(), 512);  // no checksum tag: read as it is
  }
  expect_resume_refused(opts, checkpoint, "scalars");
  std::filesystem::remove_all(root);
}
