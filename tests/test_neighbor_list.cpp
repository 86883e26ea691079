// Neighbour list against an O(N^2) brute-force search with periodic images, for a
// polydisperse packing after random displacements and after box compression; and the
// skin criterion: while no rebuild is requested, no touching pair is missing.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <vector>

#include "core/rng.hpp"
#include "exec_spaces.hpp"
#include "kernels/neighbor_list.hpp"
#include "kernels/strain.hpp"
#include "scenarios/packing.hpp"

using namespace granular;

namespace {

template <class Exec>
std::vector<std::set<int>> brute_force(const Particles<Exec>& p, const PeriodicBox& box, double extra) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.radius);
  std::vector<std::set<int>> out(p.n);
  for (int i = 0; i < p.n; ++i)
    for (int j = 0; j < p.n; ++j) {
      if (i == j) continue;
      // All 27 images, independently of the min_image helper under test.
      double best = 1e300;
      for (int sx = -1; sx <= 1; ++sx)
        for (int sy = -1; sy <= 1; ++sy)
          for (int sz = -1; sz <= 1; ++sz) {
            const double dx = x(i, 0) - x(j, 0) + sx * box.len[0];
            const double dy = x(i, 1) - x(j, 1) + sy * box.len[1];
            const double dz = x(i, 2) - x(j, 2) + sz * box.len[2];
            best = std::min(best, dx * dx + dy * dy + dz * dz);
          }
      const double cut = r(i) + r(j) + extra;
      if (best < cut * cut) out[i].insert(j);
    }
  return out;
}

template <class Exec>
std::vector<std::set<int>> listed(const NeighborList<Exec>& nl, int n) {
  auto off = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), nl.offsets());
  auto nb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), nl.neighbors());
  std::vector<std::set<int>> out(n);
  for (int i = 0; i < n; ++i)
    for (int k = off(i); k < off(i + 1); ++k) {
      EXPECT_TRUE(out[i].insert(nb(k)).second) << "pair listed twice: " << i << " " << nb(k);
    }
  return out;
}

template <class Exec>
void displace(Particles<Exec>& p, const PeriodicBox& box, double amplitude, std::uint64_t seed) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  for (int i = 0; i < p.n; ++i) {
    Stream s(seed, i);
    for (int d = 0; d < 3; ++d) x(i, d) = box.wrap(x(i, d) + s.uniform(-amplitude, amplitude), d);
  }
  Kokkos::deep_copy(p.x, x);
}

template <class Exec>
Particles<Exec> gas(PeriodicBox& box, int n, double phi) {
  GasSpec g;
  g.count = n;
  g.diameter_min = 1.0, g.diameter_max = 3.0, g.density = 1.0, g.phi = phi, g.seed = 7;
  return Particles<Exec>::from_host(random_gas(g, box));
}

}  // namespace

template <class T>
class NeighborListTest : public ::testing::Test {};
TYPED_TEST_SUITE(NeighborListTest, granular::testing::ExecSpaces);

TYPED_TEST(NeighborListTest, MatchesBruteForceWithPeriodicImagesAfterDisplacementAndCompression) {
  using Exec = TypeParam;
  PeriodicBox box;
  auto p = gas<Exec>(box, 600, 0.35);
  const double skin = 0.3;
  NeighborList<Exec> nl(skin);
  nl.build(p, box);
  EXPECT_EQ(listed(nl, p.n), brute_force(p, box, skin));

  displace(p, box, 0.7, 11);  // large moves: many particles cross periodic faces
  nl.build(p, box);
  EXPECT_EQ(listed(nl, p.n), brute_force(p, box, skin));

  const double rate[3] = {-0.2, -0.1, -0.15};
  apply_affine_strain(p, nl.reference(), box, rate, 1.0);
  nl.build(p, box);
  const auto ref = brute_force(p, box, skin);
  EXPECT_EQ(listed(nl, p.n), ref);
  size_t pairs = 0;
  for (const auto& s : ref) pairs += s.size();
  EXPECT_GT(pairs, static_cast<size_t>(p.n));  // the comparison is not vacuous
}

TYPED_TEST(NeighborListTest, SkinCriterionNeverMissesATouchingPair) {
  using Exec = TypeParam;
  PeriodicBox box;
  auto p = gas<Exec>(box, 500, 0.4);
  const double skin = 0.4;
  NeighborList<Exec> nl(skin);
  nl.build(p, box);
  // Small random moves and a compression in steps; whenever the criterion says the list
  // is still valid, every touching pair must be in it.
  int checked = 0;
  for (int k = 0; k < 40; ++k) {
    displace(p, box, 0.01, 100 + k);
    const double rate[3] = {-0.004, -0.004, -0.004};
    apply_affine_strain(p, nl.reference(), box, rate, 1.0);
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    auto xr = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), nl.reference());
    double max_sq = 0;
    for (int i = 0; i < p.n; ++i) {
      double d2 = 0;
      for (int d = 0; d < 3; ++d) d2 += std::pow(box.min_image(x(i, d) - xr(i, d), d), 2);
      max_sq = std::max(max_sq, d2);
    }
    if (nl.needs_rebuild(max_sq, box)) {
      nl.build(p, box);
      continue;
    }
    const auto touching = brute_force(p, box, 0.0);
    const auto have = listed(nl, p.n);
    for (int i = 0; i < p.n; ++i)
      for (int j : touching[i]) EXPECT_TRUE(have[i].count(j)) << "missing touching pair " << i << "-" << j;
    ++checked;
  }
  EXPECT_GT(checked, 10);
  EXPECT_GT(nl.builds(), 1);  // the criterion did fire during the compression
}
