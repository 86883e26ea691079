// The one XDMF writer (scenarios/common/xdmf.hpp) on a state written by write_state, alone and
// with walls: every HDF DataItem names a dataset of the file with as many values as its
// dimensions say, and of the type it declares; the walls' quads are a spatial collection
// beside the points; a single state is no time series. (The series' own check is in
// test_snapshot_series.cpp.)
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <filesystem>
#include <regex>
#include <sstream>

#include "core/dem/particles.hpp"
#include "core/io/output.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/xdmf.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using Exec = Kokkos::DefaultExecutionSpace;

namespace {
// Every HDF DataItem of `xdmf` names a dataset of `h5` (at `h5_name`) holding as many values
// as its dimensions say; returns how many there are.
size_t check_items(const std::string& xdmf, const std::string& h5_path,
                   const std::string& h5_name) {
  const H5Reader h5(h5_path);
  const std::regex item_re(
      "<DataItem Dimensions=\"([0-9 ]+)\" NumberType=\"(\\w+)\" Precision=\"(\\d)\" "
      "Format=\"HDF\">([^:<]+):([^<]+)</DataItem>");
  size_t items = 0;
  for (std::sregex_iterator it(xdmf.begin(), xdmf.end(), item_re), end; it != end; ++it) {
    ++items;
    EXPECT_EQ((*it)[4].str(), h5_name);
    const std::string path = (*it)[5].str(), type = (*it)[2].str();
    std::stringstream dims((*it)[1].str());
    size_t count = 1, d = 0;
    while (dims >> d) count *= d;
    EXPECT_TRUE(h5.has(path)) << path;
    if (!h5.has(path)) continue;
    const size_t stored = type == "Int" ? h5.ints(path).size() : h5.reals(path).size();
    EXPECT_EQ(stored, count) << path;
  }
  return items;
}
}  // namespace

TEST(Xdmf, StateAloneAndWithWallsNamesEveryDatasetItReads) {
  const int n = 5;
  HostParticles h;
  h.resize(n);
  for (int i = 0; i < n; ++i)
    h.x[i] = i, h.y[i] = 0.5 * i, h.z[i] = 1, h.radius[i] = 0.4, h.density[i] = 1000,
    h.species[i] = i % 2;
  const auto p = Particles<Exec>::from_host(h);
  PeriodicBox box;
  const std::string dir = granular::testing::temp_dir("xdmf_writer");
  make_directories(dir);
  {
    H5Writer out(dir + "/state.h5");
    write_state(out, "/state", p, box, 1000.0);
    // Two walls' corners, as the scenes store them (4 corners x 3 per wall).
    out.write("/walls/quads", std::vector<double>(2 * 4 * 3, 0.0));
    out.commit();
  }
  const std::string alone = xdmf_text("state.h5", {state_frame("/state", n)}, false);
  EXPECT_EQ(alone.find("Temporal"), std::string::npos);
  EXPECT_EQ(alone.find("Quadrilateral"), std::string::npos);
  EXPECT_NE(alone.find("<Grid Name=\"particles\" GridType=\"Uniform\">"), std::string::npos);
  // position, the five fields write_state stores and the box (lo, len)
  EXPECT_EQ(check_items(alone, dir + "/state.h5", "state.h5"), 8u);
  EXPECT_NE(alone.find("<Attribute Name=\"box_len\" AttributeType=\"Vector\" Center=\"Grid\">"),
            std::string::npos);

  XdmfFrame framed = state_frame("/state", n);
  framed.name = "scene", framed.nwalls = 2, framed.wall_dataset = "/walls/quads";
  write_xdmf(dir + "/scene.xdmf", "state.h5", {framed}, false);
  const std::string scene = granular::testing::read_text(dir + "/scene.xdmf");
  EXPECT_NE(scene.find("<Grid Name=\"scene\" GridType=\"Collection\" CollectionType=\"Spatial\">"),
            std::string::npos);
  EXPECT_NE(scene.find("TopologyType=\"Quadrilateral\" NumberOfElements=\"2\""), std::string::npos);
  EXPECT_EQ(check_items(scene, dir + "/state.h5", "state.h5"), 9u);
  std::filesystem::remove_all(dir);
}
