// ParaView time series: a tiny isotropic compression writes snapshots.xdmf, a temporal
// collection with one frame per due sample, the right point count in every frame and every
// HDF5 item it references present with matching dimensions; an impact on a wall adds the
// wall as a quad to each frame; an unfinished series leaves no file. When ParaView's
// `pvpython` is installed, its own XDMF reader loads the series and reads back the engine's
// values and box.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"
#include "kernels/contact/contact_model.hpp"
#include "scenarios/collisions/impact.hpp"
#include "scenarios/common/snapshot_series.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/external_program.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::read_text;
namespace fs = std::filesystem;

namespace {

constexpr int kParticles = 40;
constexpr long kEvery = 120;

const char* const kScene = R"(scene = "isotropic_compression"
[particles]
count = 40
diameter_min = 1.0
diameter_max = 1.4
density = 2000.0
seed = 3
initial_speed = 1.0e-4
[contact]
kn = 1.0e5
gamma_n = 1000.0
[damping]
background = 100.0
[compression]
phi_start = 0.3
phi_end = 0.45
volumetric_strain_rate = 0.05
relax_steps = 100
[run]
dt = 0.004
skin = 0.2
sample_every = 50
checkpoint_every = 100000
[output]
snapshot_every = 120
)";

struct Frame {
  long step;
  double time;
};

// Checks a series' XDMF against its HDF5 file: every frame's point count, and every HDF
// DataItem naming a dataset of that file with as many values as its dimensions say.
// Returns the frames in file order.
std::vector<Frame> check_series(const std::string& dir, const std::string& name, int n,
                                int nwalls) {
  const std::string xdmf = read_text(dir + "/" + name + ".xdmf");
  EXPECT_NE(xdmf.find("CollectionType=\"Temporal\""), std::string::npos);
  H5Reader h5(dir + "/" + name + ".h5");
  std::vector<Frame> frames;
  const std::regex frame_re("<Grid Name=\"step_(\\d+)\"[^>]*>\\s*<Time Value=\"([^\"]+)\"/>");
  for (std::sregex_iterator it(xdmf.begin(), xdmf.end(), frame_re), end; it != end; ++it) {
    const long step = std::stol((*it)[1].str());
    const double t = std::stod((*it)[2].str());
    frames.push_back({step, t});
    EXPECT_DOUBLE_EQ(h5.attribute(snapshot_group(step), "time"), t);
  }
  const std::regex poly_re("TopologyType=\"Polyvertex\" NumberOfElements=\"(\\d+)\"");
  size_t grids = 0;
  for (std::sregex_iterator it(xdmf.begin(), xdmf.end(), poly_re), end; it != end; ++it, ++grids)
    EXPECT_EQ(std::stoi((*it)[1].str()), n);
  EXPECT_EQ(grids, frames.size());
  const std::regex quad_re("TopologyType=\"Quadrilateral\" NumberOfElements=\"(\\d+)\"");
  size_t wall_grids = 0;
  for (std::sregex_iterator it(xdmf.begin(), xdmf.end(), quad_re), end; it != end;
       ++it, ++wall_grids)
    EXPECT_EQ(std::stoi((*it)[1].str()), nwalls);
  EXPECT_EQ(wall_grids, nwalls > 0 ? frames.size() : 0u);
  const std::regex item_re(
      "<DataItem Dimensions=\"([0-9 ]+)\" NumberType=\"(\\w+)\" Precision=\"(\\d)\" "
      "Format=\"HDF\">([^:<]+):([^<]+)</DataItem>");
  size_t items = 0;
  for (std::sregex_iterator it(xdmf.begin(), xdmf.end(), item_re), end; it != end; ++it) {
    ++items;
    const std::string file = (*it)[4].str(), path = (*it)[5].str();
    EXPECT_EQ(file, name + ".h5");
    std::stringstream dims((*it)[1].str());
    size_t count = 1, d = 0;
    while (dims >> d) count *= d;
    EXPECT_TRUE(h5.has(path)) << path << " is not in " << file;
    if (h5.has(path)) {
      EXPECT_EQ(h5.reals(path).size(), count) << path;
    }
  }
  // Per frame: position, six attributes and the box (lo, len) (+ the wall quads).
  EXPECT_EQ(items, frames.size() * (9 + (nwalls > 0 ? 1 : 0)));
  for (size_t k = 1; k < frames.size(); ++k) {
    EXPECT_GT(frames[k].step, frames[k - 1].step);
    EXPECT_GT(frames[k].time, frames[k - 1].time);
  }
  return frames;
}

class SnapshotSeriesTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = granular::testing::temp_dir("snapshots");
    RunOptions opts;
    opts.out_dir = dir_;
    opts.progress = false;
    opts.charts = false;
    const SceneFile scene = SceneFile::parse(kScene, "tiny_compression.toml");
    scene.text("scene");  // read by the CLI to pick the driver
    run_isotropic_compression(scene, opts);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string dir_;
};
std::string SnapshotSeriesTest::dir_;

}  // namespace

TEST_F(SnapshotSeriesTest, CompressionSeriesHasEveryDueFrameAndConsistentData) {
  ASSERT_TRUE(fs::exists(dir_ + "/snapshots.h5"));
  ASSERT_TRUE(fs::exists(dir_ + "/snapshots.xdmf"));
  // The frames due: the start, then the first sample at or after each multiple of k, and
  // the end.
  H5Reader results(dir_ + "/results.h5");
  const auto sampled = results.reals("/series/step");
  std::vector<long> due = {static_cast<long>(sampled.front())};
  for (double s : sampled)
    if (static_cast<long>(s) / kEvery != due.back() / kEvery) due.push_back(static_cast<long>(s));
  if (due.back() != static_cast<long>(sampled.back()))
    due.push_back(static_cast<long>(sampled.back()));
  const auto frames = check_series(dir_, "snapshots", kParticles, 0);
  ASSERT_EQ(frames.size(), due.size());
  for (size_t k = 0; k < due.size(); ++k) EXPECT_EQ(frames[k].step, due[k]);
  EXPECT_GT(frames.size(), 10u);
  // The last frame is the final state of results.h5, row for row.
  H5Reader snaps(dir_ + "/snapshots.h5");
  EXPECT_EQ(snaps.reals(snapshot_group(frames.back().step) + "/position"),
            results.reals("/final_state/position"));
  EXPECT_FALSE(fs::exists(dir_ + "/.snapshots.h5.partial"));
}

TEST(SnapshotSeries, ImpactOnAWallShowsTheWallInEveryFrame) {
  const std::string dir = granular::testing::temp_dir("snapshots_wall");
  fs::create_directories(dir);
  const ContactModel<LinearNormal> model{LinearNormal::uniform(1e3, 0.0), {}, {}};
  {
    SnapshotSeries series(dir, "impact", 10);
    ImpactSetup s;
    s.radius1 = 1.0, s.density1 = 1.0, s.speed = 0.01, s.dt = 2e-3;
    s.snapshots = &series;
    const auto r = impact<Kokkos::DefaultExecutionSpace>(model, s);
    ASSERT_TRUE(r.separated);
    EXPECT_EQ(series.frames(), static_cast<int>(r.steps / 10 + 1 + (r.steps % 10 ? 1 : 0)));
  }
  const auto frames = check_series(dir, "impact", 1, 1);
  // The wall is the plane z = 0 in every frame.
  H5Reader h5(dir + "/impact.h5");
  for (const auto& f : frames) {
    const auto q = h5.reals(snapshot_group(f.step) + "/walls/quads");
    ASSERT_EQ(q.size(), 12u);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(q[3 * c + 2], 0.0, 1e-12);
  }
  fs::remove_all(dir);
}

// Two spheres apart in a periodic box: a system to sample, for the tests of the series' files.
using TwoSpheres = DemSystem<Kokkos::DefaultExecutionSpace, ContactModel<LinearNormal>>;
TwoSpheres two_spheres() {
  const ContactModel<LinearNormal> model{LinearNormal::uniform(1e3, 0.0), {}, {}};
  HostParticles h;
  h.resize(2);
  h.x = {0, 3}, h.y = {0, 0}, h.z = {0, 0}, h.radius = {1, 1}, h.density = {1, 1};
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = -10, box.len[d] = 20;
  DemParams prm;
  prm.dt = 1e-3, prm.skin = 0.2;
  return TwoSpheres(Particles<Kokkos::DefaultExecutionSpace>::from_host(h), box, model, prm);
}

TEST(SnapshotSeries, UnfinishedSeriesLeavesNoFile) {
  const std::string dir = granular::testing::temp_dir("snapshots_unfinished");
  fs::create_directories(dir);
  TwoSpheres sys = two_spheres();
  {
    SnapshotSeries series(dir, "cut", 5);
    series.sample(sys);
    sys.step(5);
    series.sample(sys);
    EXPECT_EQ(series.frames(), 2);
  }  // the run stops here, as if interrupted
  EXPECT_TRUE(fs::is_empty(dir));
  {
    SnapshotSeries off(dir, "off", 0);  // k = 0: no series at all
    off.sample(sys);
    off.finish(sys);
  }
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

// A resumed run starts its series afresh: the XDMF file of the earlier version names frames
// the new .h5 does not hold, so it goes before the new .h5 is committed. Here the new .h5
// cannot be committed at all (a folder holds its name): the earlier XDMF must be gone, never
// left beside a file it does not describe (a kill between the two commits did that).
TEST(SnapshotSeries, EarlierSeriesXdmfIsRemovedBeforeTheNewSeriesIsCommitted) {
  const std::string dir = granular::testing::temp_dir("snapshots_resumed");
  fs::create_directories(dir);
  TwoSpheres sys = two_spheres();
  {
    SnapshotSeries first(dir, "s", 5);
    first.sample(sys);
    sys.step(5);
    first.finish(sys);
  }
  ASSERT_TRUE(fs::exists(dir + "/s.xdmf"));
  fs::remove(dir + "/s.h5");
  fs::create_directories(dir + "/s.h5/in_the_way");
  {
    SnapshotSeries resumed(dir, "s", 5);
    sys.step(5);
    resumed.sample(sys);
    EXPECT_ANY_THROW(resumed.finish(sys));
  }
  EXPECT_FALSE(fs::exists(dir + "/s.xdmf"));
  fs::remove_all(dir);
}

// ParaView's own XDMF reader (pvpython or pvbatch from Debian's ParaView) loads the series: as many
// time steps as frames, the particle count and every field in each, and the values it reads
// (positions, velocities, radii, and each frame's box as the grid's field data) are the
// engine's to the last bit.
TEST_F(SnapshotSeriesTest, ParaViewReadsTheSeriesWithItsBoxAndTheEnginesValues) {
  // pvpython, or pvbatch (Debian 12's paraview ships only pvbatch): the same interpreter.
  std::string pvpython = granular::testing::find_program("pvpython");
  if (pvpython.empty()) pvpython = granular::testing::find_program("pvbatch");
  if (pvpython.empty())
    GTEST_SKIP() << "neither pvpython nor pvbatch is installed (Debian packages `paraview`, "
                    "`python3-paraview`): series not opened in ParaView";
  const auto frames = check_series(dir_, "snapshots", kParticles, 0);
  const std::string script = dir_ + "/load_series.py", log = dir_ + "/pvpython.txt",
                    values = dir_ + "/pvpython_values.txt";
  std::ofstream(script) << R"(import sys
from paraview import simple, servermanager
path, frames, points, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
try:
    reader = simple.Xdmf3ReaderS(FileName=[path])
except AttributeError:
    reader = simple.XDMFReader(FileNames=[path])
times = list(reader.TimestepValues)
assert len(times) == frames, "time steps %d, frames %d" % (len(times), frames)
fields = ["radius", "velocity", "angular_velocity", "force", "species", "id"]
with open(out, "w") as o:
    for t in times:
        reader.UpdatePipeline(t)
        data = servermanager.Fetch(reader)
        if data.IsA("vtkMultiBlockDataSet"):
            data = data.GetBlock(0)
        n = data.GetNumberOfPoints()
        assert n == points, "t %g: %d points" % (t, n)
        for f in fields:
            a = data.GetPointData().GetArray(f)
            assert a is not None and a.GetNumberOfTuples() == points, "t %g: field %s" % (t, f)
        # repr: the shortest text that reads back as the same double
        row = lambda name, vals: o.write(name + " " + " ".join(repr(float(v)) for v in vals) + "\n")
        for b in ("box_lo", "box_len"):
            a = data.GetFieldData().GetArray(b)
            assert a is not None, "t %g: no field data %s" % (t, b)
            row(b, [a.GetValue(c) for c in range(a.GetNumberOfValues())])
        row("position", [c for i in range(n) for c in data.GetPoint(i)])
        for f in ("velocity", "radius"):
            a = data.GetPointData().GetArray(f)
            row(f, [a.GetValue(c) for c in range(a.GetNumberOfValues())])
print("series ok: %d time steps" % len(times))
)";
  const int rc = granular::testing::run_program(
      {pvpython, "--force-offscreen-rendering", script, dir_ + "/snapshots.xdmf",
       std::to_string(frames.size()), std::to_string(kParticles), values},
      log);
  const std::string out = read_text(log);
  if (out.find("No module named 'paraview'") != std::string::npos)
    GTEST_SKIP() << pvpython << " has no paraview module (Debian package `python3-paraview`)";
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("series ok"), std::string::npos) << out;
  // What ParaView read, frame by frame, against the series' HDF5 file.
  H5Reader h5(dir_ + "/snapshots.h5");
  std::istringstream read(read_text(values));
  std::string line;
  size_t lines = 0;
  for (const Frame& f : frames)
    for (const char* name : {"box_lo", "box_len", "position", "velocity", "radius"}) {
      ASSERT_TRUE(std::getline(read, line)) << "ParaView's values end before frame " << f.step;
      ++lines;
      std::istringstream fields(line);
      std::string got_name;
      fields >> got_name;
      ASSERT_EQ(got_name, name);
      std::vector<double> got;
      for (std::string v; fields >> v;) got.push_back(std::stod(v));
      EXPECT_EQ(got, h5.reals(snapshot_group(f.step) + "/" + name))
          << name << " of step " << f.step << " as ParaView reads it";
    }
  EXPECT_EQ(lines, frames.size() * 5);
  // The box deforms over the compression: the frames do not all show the same box.
  EXPECT_NE(h5.reals(snapshot_group(frames.front().step) + "/box_len"),
            h5.reals(snapshot_group(frames.back().step) + "/box_len"));
}
