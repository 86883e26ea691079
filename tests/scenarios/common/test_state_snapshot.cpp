// A particle snapshot (write_state) read back (read_state) gives every particle its own
// position, velocity, spin, radius and species, in identity order, whatever order the engine
// keeps its arrays in; a snapshot written before spins and species were stored still reads.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <filesystem>

#include "core/dem/particles.hpp"
#include "core/io/output.hpp"
#include "scenarios/common/dem_output.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using Exec = Kokkos::DefaultExecutionSpace;

namespace {

HostParticles distinct_particles(int n) {
  HostParticles h;
  h.resize(n);
  for (int i = 0; i < n; ++i) {
    h.x[i] = 1.0 + i, h.y[i] = 2.0 + 0.5 * i, h.z[i] = 3.0 - 0.25 * i;
    h.vx[i] = 0.1 * i, h.vy[i] = -0.2 * i, h.vz[i] = 0.3;
    h.wx[i] = 0.01 * i, h.wy[i] = -0.02, h.wz[i] = 0.03 * i * i;
    h.radius[i] = 0.5 + 0.01 * i;
    h.density[i] = 2000.0;
    h.species[i] = i % 3;
  }
  return h;
}

}  // namespace

TEST(StateSnapshot, RoundTripKeepsSpinsSpeciesAndIdentityOrderAfterReordering) {
  const int n = 7;
  const HostParticles h = distinct_particles(n);
  auto p = Particles<Exec>::from_host(h);
  // Reverse the arrays, as a locality sort would reorder them.
  Particles<Exec>::int_view order("order", n);
  auto oh = Kokkos::create_mirror_view(order);
  for (int i = 0; i < n; ++i) oh(i) = n - 1 - i;
  Kokkos::deep_copy(order, oh);
  p.permute(order);

  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = -1.0 * d, box.len[d] = 10.0 + d;
  const std::string dir = granular::testing::temp_dir("state_snapshot");
  make_directories(dir);
  const std::string path = dir + "/state.h5";
  {
    H5Writer out(path);
    write_state(out, "/state", p, box, 2000.0);
    out.commit();
  }
  H5Reader in(path);
  PeriodicBox back;
  double density = 0;
  const HostParticles r = read_state(in, "/state", back, density);
  ASSERT_EQ(r.size(), n);
  EXPECT_EQ(density, 2000.0);
  const auto ids = in.ints("/state/id");
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(ids[i], i);
    EXPECT_EQ(r.x[i], h.x[i]) << i;
    EXPECT_EQ(r.z[i], h.z[i]) << i;
    EXPECT_EQ(r.vy[i], h.vy[i]) << i;
    EXPECT_EQ(r.wx[i], h.wx[i]) << i;
    EXPECT_EQ(r.wz[i], h.wz[i]) << i;
    EXPECT_EQ(r.radius[i], h.radius[i]) << i;
    EXPECT_EQ(r.species[i], h.species[i]) << i;
  }
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(back.lo[d], box.lo[d]);
    EXPECT_EQ(back.len[d], box.len[d]);
  }

  // The spins reach the particle store of the restarted system.
  const auto q = Particles<Exec>::from_host(r);
  auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), q.w);
  for (int i = 0; i < n; ++i) EXPECT_EQ(w(i, 2), h.wz[i]) << i;
  std::filesystem::remove_all(dir);
}

TEST(StateSnapshot, SnapshotWithoutSpinsOrSpeciesReadsAsAtRestSpeciesZero) {
  const std::string dir = granular::testing::temp_dir("state_snapshot_old");
  make_directories(dir);
  const std::string path = dir + "/old.h5";
  {
    H5Writer out(path);
    out.write("/state/position", std::vector<double>{0, 0, 0, 1, 1, 1}, {2, 3});
    out.write("/state/velocity", std::vector<double>{0, 0, 1, 0, 0, -1}, {2, 3});
    out.write("/state/radius", std::vector<double>{0.5, 0.5});
    out.write("/state/box_lo", std::vector<double>{0, 0, 0});
    out.write("/state/box_len", std::vector<double>{4, 4, 4});
    out.attribute("/state", "density", 1000.0);
    out.commit();
  }
  H5Reader in(path);
  PeriodicBox box;
  double density = 0;
  const HostParticles r = read_state(in, "/state", box, density);
  ASSERT_EQ(r.size(), 2);
  EXPECT_EQ(r.vz[1], -1.0);
  EXPECT_EQ(r.wx[0], 0.0);
  EXPECT_EQ(r.species[1], 0);
  std::filesystem::remove_all(dir);
}
