// Neighbour list against an O(N^2) brute-force search with periodic images, for a
// polydisperse packing after random displacements and after box compression; and the
// skin criterion: while no rebuild is requested, no touching pair is missing; the owned-first
// order, the mirror entries and the pair index the force loops rely on.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <set>
#include <vector>

#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "core/run/rng.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "kernels/dem/neighbor_list.hpp"
#include "kernels/dem/strain.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/restart_file.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

template <class Exec>
std::vector<std::set<int>> brute_force(const Particles<Exec>& p, const PeriodicBox& box,
                                       double extra) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.radius);
  std::vector<std::set<int>> out(p.n);
  for (int i = 0; i < p.n; ++i)
    for (int j = 0; j < p.n; ++j) {
      if (i == j) continue;
      // All 27 images (on periodic axes), independently of the min_image helper under test.
      double best = 1e300;
      const int ex = box.periodic[0], ey = box.periodic[1], ez = box.periodic[2];
      for (int sx = -ex; sx <= ex; ++sx)
        for (int sy = -ey; sy <= ey; ++sy)
          for (int sz = -ez; sz <= ez; ++sz) {
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

// Structure the force loops rely on: each particle's entries hold the partners with a
// higher identity first (up to owned_end), and mirror(k) is the entry of the same pair in
// the partner's list.
template <class Exec>
void check_owned_first_and_mirror(const NeighborList<Exec>& nl, const Particles<Exec>& p) {
  const auto h = Kokkos::HostSpace();
  auto off = Kokkos::create_mirror_view_and_copy(h, nl.offsets());
  auto nb = Kokkos::create_mirror_view_and_copy(h, nl.neighbors());
  auto mir = Kokkos::create_mirror_view_and_copy(h, nl.mirror());
  auto own = Kokkos::create_mirror_view_and_copy(h, nl.owned_end());
  auto id = Kokkos::create_mirror_view_and_copy(h, p.id);
  long owned = 0;
  for (int i = 0; i < p.n; ++i) {
    ASSERT_GE(own(i), off(i));
    ASSERT_LE(own(i), off(i + 1));
    owned += own(i) - off(i);
    for (int k = off(i); k < off(i + 1); ++k) {
      const int j = nb(k), m = mir(k);
      EXPECT_EQ(k<own(i), id(j)> id(i)) << "entry " << k << " of particle " << i;
      ASSERT_GE(m, off(j));
      ASSERT_LT(m, off(j + 1));
      EXPECT_EQ(nb(m), i);
      EXPECT_EQ(mir(m), k);
    }
  }
  EXPECT_EQ(2 * owned, static_cast<long>(nl.num_entries()));  // every pair owned once
  // The pair index: row r = pair_begin(i) + (k - offsets(i)) of owned entry k belongs to i,
  // and both entries of a pair name the same row (the owner's).
  ASSERT_EQ(nl.num_pairs(), owned);
  ASSERT_GT(nl.pair_owner().extent(0), 0u) << "the test lists keep the pair index";
  auto begin = Kokkos::create_mirror_view_and_copy(h, nl.pair_begin());
  auto owner = Kokkos::create_mirror_view_and_copy(h, nl.pair_owner());
  auto prow = Kokkos::create_mirror_view_and_copy(h, nl.pair_row());
  std::vector<int> seen(owned, 0);
  for (int i = 0; i < p.n; ++i)
    for (int k = off(i); k < off(i + 1); ++k) {
      const int j = nb(k), r = prow(k);
      const int o = k < own(i) ? i : j;  // the pair's owner
      const int ko = k < own(i) ? k : mir(k);
      ASSERT_EQ(r, begin(o) + ko - off(o)) << "entry " << k << " of particle " << i;
      EXPECT_EQ(owner(r), o);
      ++seen[r];
    }
  for (long r = 0; r < owned; ++r) EXPECT_EQ(seen[r], 2) << "row " << r;
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
  nl.keep_pair_index(true);
  nl.build(p, box);
  EXPECT_EQ(listed(nl, p.n), brute_force(p, box, skin));
  check_owned_first_and_mirror(nl, p);

  displace(p, box, 0.7, 11);  // large moves: many particles cross periodic faces
  nl.build(p, box);
  EXPECT_EQ(listed(nl, p.n), brute_force(p, box, skin));
  check_owned_first_and_mirror(nl, p);

  const double rate[3] = {-0.2, -0.1, -0.15};
  apply_affine_strain(p, nl.reference(), box, rate, 1.0);
  nl.build(p, box);
  const auto ref = brute_force(p, box, skin);
  EXPECT_EQ(listed(nl, p.n), ref);
  size_t pairs = 0;
  for (const auto& s : ref) pairs += s.size();
  EXPECT_GT(pairs, static_cast<size_t>(p.n));  // the comparison is not vacuous
}

// The stencil skips cells beyond a particle's largest cutoff: exact also where particles
// overlap a wall (outside the box, binned into the edge cells) and along a periodic axis of
// only two cells (where nothing may be skipped).
TYPED_TEST(NeighborListTest, MatchesBruteForceInAWalledBoxAndAlongAnAxisOfTwoCells) {
  using Exec = TypeParam;
  PeriodicBox box;
  auto p = gas<Exec>(box, 600, 0.35);
  const double skin = 0.3;
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.radius);
  double a_max = 0;
  for (int i = 0; i < p.n; ++i) a_max = std::max(a_max, r(i));
  // x squeezed to 2.2 cutoffs: two cells, both neighbours of each other on either side.
  const double squeeze = 2.2 * (2 * a_max + skin) / box.len[0];
  for (int i = 0; i < p.n; ++i) x(i, 0) = box.lo[0] + (x(i, 0) - box.lo[0]) * squeeze;
  box.len[0] *= squeeze;
  box.periodic[2] = false;  // walls at z = lo and lo + len, some particles beyond them
  for (int i = 0; i < p.n; i += 37) x(i, 2) = box.lo[2] - 0.4 * r(i);
  for (int i = 18; i < p.n; i += 37) x(i, 2) = box.lo[2] + box.len[2] + 0.4 * r(i);
  Kokkos::deep_copy(p.x, x);
  NeighborList<Exec> nl(skin);
  nl.keep_pair_index(true);
  nl.build(p, box);
  const auto ref = brute_force(p, box, skin);
  EXPECT_EQ(listed(nl, p.n), ref);
  check_owned_first_and_mirror(nl, p);
  size_t pairs = 0;
  for (const auto& s : ref) pairs += s.size();
  EXPECT_GT(pairs, static_cast<size_t>(p.n));  // the comparison is not vacuous
}

// The cell order (slabs along z, blocks of cell rows along y inside each) is a relabelling of
// the cells: every cell keeps one position of its own, whatever the partition, and the list is
// the brute-force one; every listed pair joins particles of the same or adjacent slabs (what
// lets the three rounds of the host force pass scatter without races).
TYPED_TEST(NeighborListTest, EveryCellOrderIsAPermutationOfTheCellsAndListsEveryPairOnce) {
  using Exec = TypeParam;
  const double skin = 0.3;
  struct Partition {
    int slabs, rows;
  };
  for (const bool periodic_z : {true, false})
    for (const Partition part : {Partition{0, 4}, Partition{0, 1}, Partition{3, 2}, Partition{7, 3},
                                 Partition{100, 1000}, Partition{1, 5}}) {
      PeriodicBox box;
      auto p = gas<Exec>(box, 1500, 0.3);
      box.periodic[2] = periodic_z;
      NeighborList<Exec> nl(skin);
      nl.set_partition(part.slabs, part.rows);
      nl.build(p, box);
      const std::string where = std::string(periodic_z ? "periodic" : "walled") + " z, slabs " +
                                std::to_string(part.slabs) + ", rows " + std::to_string(part.rows);
      const auto hs = Kokkos::HostSpace();
      auto rank = Kokkos::create_mirror_view_and_copy(hs, nl.cell_rank());
      const int ncells = static_cast<int>(rank.extent(0));
      ASSERT_GE(ncells, 27) << where;
      std::vector<int> seen(ncells, 0);
      for (int c = 0; c < ncells; ++c) {
        ASSERT_GE(rank(c), 0) << where;
        ASSERT_LT(rank(c), ncells) << where;
        ++seen[rank(c)];
      }
      EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), ncells) << where;
      const int slabs = nl.num_slabs();
      if (periodic_z && slabs > 1) {
        EXPECT_EQ(slabs % 3, 0) << where;
      }
      if (part.slabs > 0 && part.slabs <= 3) {
        EXPECT_EQ(slabs, part.slabs == 3 ? 3 : 1) << where;
      }
      EXPECT_EQ(listed(nl, p.n), brute_force(p, box, skin)) << where;
      auto begin = Kokkos::create_mirror_view_and_copy(hs, nl.slab_begin());
      auto order = Kokkos::create_mirror_view_and_copy(hs, nl.cell_order());
      auto off = Kokkos::create_mirror_view_and_copy(hs, nl.offsets());
      auto nb = Kokkos::create_mirror_view_and_copy(hs, nl.neighbors());
      std::vector<int> slab_of(p.n, -1);
      for (int s = 0; s < slabs; ++s)
        for (int q = begin(s); q < begin(s + 1); ++q) slab_of[order(q)] = s;
      long across = 0;
      for (int i = 0; i < p.n; ++i) {
        ASSERT_GE(slab_of[i], 0) << where;
        for (int k = off(i); k < off(i + 1); ++k) {
          const int d = std::abs(slab_of[i] - slab_of[nb(k)]);
          const int gap = periodic_z ? std::min(d, slabs - d) : d;
          ASSERT_LE(gap, 1) << where;
          across += gap;
        }
      }
      if (slabs > 1) {
        EXPECT_GT(across, 0) << where << ": no pair crosses a slab face, the check is vacuous";
      }
    }
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
      for (int j : touching[i])
        EXPECT_TRUE(have[i].count(j)) << "missing touching pair " << i << "-" << j;
    ++checked;
  }
  EXPECT_GT(checked, 10);
  EXPECT_GT(nl.builds(), 1);  // the criterion did fire during the compression
}

// A particle with far more partners than the one-sweep build keeps per row (a large sphere
// among small ones) sends the build down its second sweep; the list must still be exact,
// then and at the next build, when the per-row capacity has grown as far as it may.
TYPED_TEST(NeighborListTest, CrowdedParticleBeyondTheRowCapacityIsListedExactly) {
  using Exec = TypeParam;
  PeriodicBox box;
  // The box is just over twice the big particle's cutoff (2 x 5 + skin), the least the
  // minimum image allows, to keep the brute-force reference small.
  const double L = 22.0, c = L / 2;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0.0, box.len[d] = L;
  std::vector<std::array<double, 4>> balls = {{c, c, c, 5.0}};  // the crowded one
  for (int a = 0; a < 22; ++a)
    for (int b = 0; b < 22; ++b)
      for (int k = 0; k < 22; k += 2) {
        const double x = a + 0.5, y = b + 0.5, z = k + 0.5 + 0.5 * (a % 2);
        const double d2 = std::pow(x - c, 2) + std::pow(y - c, 2) + std::pow(z - c, 2);
        if (d2 < 5.6 * 5.6) continue;  // keep the big one free of overlaps
        balls.push_back({x, y, z, 0.45});
      }
  HostParticles h;
  h.resize(static_cast<int>(balls.size()));
  for (size_t i = 0; i < balls.size(); ++i) {
    h.x[i] = balls[i][0], h.y[i] = balls[i][1], h.z[i] = balls[i][2];
    h.radius[i] = balls[i][3], h.density[i] = 1.0;
  }
  auto p = Particles<Exec>::from_host(h);
  const double skin = 0.8;
  NeighborList<Exec> nl(skin);
  nl.keep_pair_index(true);
  for (int build = 0; build < 2; ++build) {
    nl.build(p, box);
    const auto ref = brute_force(p, box, skin);
    ASSERT_GT(ref[0].size(), 100u) << "the big particle must exceed any row capacity";
    EXPECT_EQ(listed(nl, p.n), ref);
    check_owned_first_and_mirror(nl, p);
    displace(p, box, 0.02, 40 + build);
  }
}

// With the particles stored in cell order (DemSystem's sorting), host builds test four
// candidates at a time (kernels/cpu/neighbor_sweep.hpp). The list must be the scalar sweep's,
// entry for entry (the force sums follow its order), and the brute-force set: in a periodic
// and a walled box, with a particle count that leaves a partial vector at the array's end, and
// with a crowded particle whose row outgrows the build's scratch.
TYPED_TEST(NeighborListTest, VectorSweepInCellOrderListsTheScalarSweepsEntriesInItsOrder) {
  using Exec = TypeParam;
  const auto hs = Kokkos::HostSpace();
  for (const bool periodic_z : {true, false})
    for (const bool crowded : {false, true}) {
      PeriodicBox box;
      auto p = gas<Exec>(box, 1499, 0.3);
      box.periodic[2] = periodic_z;
      if (crowded) {  // one particle grown to reach ~120 others
        auto r = Kokkos::create_mirror_view_and_copy(hs, p.radius);
        r(700) = 6.0;
        Kokkos::deep_copy(p.radius, r);
      }
      const double skin = 0.3;
      NeighborList<Exec> fast(skin), plain(skin);
      fast.keep_pair_index(true);
      fast.bin(p, box);
      typename Particles<Exec>::int_view order("order", p.n);
      Kokkos::deep_copy(order, Kokkos::subview(fast.cell_order(), std::make_pair(0, p.n)));
      p.permute(order);
      const std::string where = std::string(periodic_z ? "periodic" : "walled") + " z" +
                                (crowded ? ", a crowded particle" : "");
      for (int build = 0; build < 2; ++build) {  // the second with the scratch grown
        fast.build(p, box, true);                // relabelled cells: the four-at-a-time sweep
        plain.build(p, box);                     // binned again: the same cells, the scalar sweep
        auto off_f = Kokkos::create_mirror_view_and_copy(hs, fast.offsets());
        auto off_p = Kokkos::create_mirror_view_and_copy(hs, plain.offsets());
        auto own_f = Kokkos::create_mirror_view_and_copy(hs, fast.owned_end());
        auto own_p = Kokkos::create_mirror_view_and_copy(hs, plain.owned_end());
        auto nb_f = Kokkos::create_mirror_view_and_copy(hs, fast.neighbors());
        auto nb_p = Kokkos::create_mirror_view_and_copy(hs, plain.neighbors());
        ASSERT_EQ(fast.num_entries(), plain.num_entries()) << where;
        for (int i = 0; i <= p.n; ++i) ASSERT_EQ(off_f(i), off_p(i)) << where << ", row " << i;
        for (int i = 0; i < p.n; ++i) ASSERT_EQ(own_f(i), own_p(i)) << where << ", row " << i;
        for (int k = 0; k < fast.num_entries(); ++k)
          ASSERT_EQ(nb_f(k), nb_p(k)) << where << ", entry " << k;
        const auto ref = brute_force(p, box, skin);
        EXPECT_EQ(listed(fast, p.n), ref) << where;
        check_owned_first_and_mirror(fast, p);
        size_t most = 0;
        for (const auto& s : ref) most = std::max(most, s.size());
        if (crowded) {
          EXPECT_GT(most, 64u) << where << ": the crowded row must outgrow the scratch";
        }
      }
    }
}

#include "kernels/dem/strain_modes.hpp"

// A checkpoint's list with an index out of range is refused on load, naming its group,
// instead of being read out of bounds on the first force pass (a segfault before).
TYPED_TEST(NeighborListTest, DamagedListInACheckpointIsRefusedOnLoad) {
  using Exec = TypeParam;
  PeriodicBox box;
  auto p = gas<Exec>(box, 300, 0.35);
  NeighborList<Exec> nl(0.3);
  nl.build(p, box);
  // Per process: ctest runs the one- and two-thread variants at once.
  const auto dir_path = granular::testing::unique_temp_path("granular_list");
  std::filesystem::create_directories(dir_path);
  const std::string dir = dir_path.string() + "/";
  {
    H5Writer w(dir + "granular_list_ok.h5");
    write_list(w, "list", nl.saved());
    w.commit();
  }
  const H5Reader good(dir + "granular_list_ok.h5");
  NeighborList<Exec> copy(0.3);
  load_list(good, "list", copy);  // the intact list loads
  // Rewrites the list with one integer dataset changed at `at` to `value`.
  auto damaged = [&](const std::string& name, size_t at, int value) {
    const std::string path = dir + "granular_list_bad.h5";
    H5Writer w(path);
    for (const char* d :
         {"offsets", "neighbors", "mirror", "owned_end", "cell_order", "slab_begin"}) {
      const std::string ds = std::string("list/") + d;
      if (!good.has(ds)) continue;
      std::vector<int> v = good.ints(ds);
      if (name == d) v.at(at) = value;
      w.write(ds, v);
      w.attribute(ds, "extent0", good.attribute(ds, "extent0"));
      w.attribute(ds, "extent1", good.attribute(ds, "extent1"));
    }
    w.write("list/x_ref", good.reals("list/x_ref"));
    w.attribute("list/x_ref", "extent0", good.attribute("list/x_ref", "extent0"));
    w.attribute("list/x_ref", "extent1", good.attribute("list/x_ref", "extent1"));
    w.write("list/scalars", good.reals("list/scalars"));
    w.commit();
    return path;
  };
  const std::pair<const char*, int> cases[] = {
      {"neighbors", p.n},   {"neighbors", -1}, {"cell_order", p.n + 5}, {"cell_order", -3},
      {"offsets", 1 << 30}, {"owned_end", -7}, {"slab_begin", p.n + 1}};
  for (const auto& [name, value] : cases) {
    const std::string path = damaged(name, 1, value);
    const H5Reader bad(path);
    NeighborList<Exec> l(0.3);
    try {
      load_list(bad, "list", l);
      ADD_FAILURE() << name << " = " << value << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("restart group list"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir_path);
}

// A box compressed through zero (or made non-finite) is reported as collapsed, with the
// advice to lower the rate, not "use more particles" (and no NaN reaches the cell count).
TYPED_TEST(NeighborListTest, CollapsedBoxIsReportedAsCollapsed) {
  using Exec = TypeParam;
  PeriodicBox box;
  auto p = gas<Exec>(box, 300, 0.35);
  NeighborList<Exec> nl(0.3);
  for (double edge : {-111.0, 0.0, std::nan("")}) {
    PeriodicBox bad = box;
    bad.len[1] = edge;
    try {
      nl.build(p, bad);
      ADD_FAILURE() << "edge " << edge << " accepted";
    } catch (const PhysicsError& e) {
      EXPECT_NE(std::string(e.what()).find("along y is not a positive length"), std::string::npos)
          << e.what();
      EXPECT_EQ(std::string(e.what()).find("more particles"), std::string::npos) << e.what();
    }
  }
}

TEST(StrainModes, PureShearConservesVolumeAndTrueStrainsAdd) {
  PeriodicBox box, ref;
  for (int d = 0; d < 3; ++d) box.len[d] = ref.len[d] = 10.0;
  Particles<Kokkos::DefaultExecutionSpace> p(1);
  Kokkos::View<double* [3], Kokkos::DefaultExecutionSpace::memory_space> xr("xr", 1);
  const auto r = strain_rates("pure_shear", 1e-3);
  // In exact arithmetic (1 + e dt)(1 - e dt) = 1 - (e dt)^2: the volume change is second
  // order in the step, so 1000 steps of 1e-3 change it by about 1e-3 relative.
  for (int k = 0; k < 1000; ++k) apply_affine_strain(p, xr, box, r.data(), 1.0);
  EXPECT_NEAR(box.volume() / ref.volume(), 1.0, 1.1e-3);
  const auto e = true_strain(box, ref);
  EXPECT_NEAR(e[0], 1000 * std::log1p(1e-3), 1e-12);
  EXPECT_NEAR(e[1], 1000 * std::log1p(-1e-3), 1e-12);
  EXPECT_DOUBLE_EQ(e[2], 0.0);
  EXPECT_THROW(strain_rates("shearing", 1.0), InputError);
}

TEST(Measurements, ChiHistogramAndFabricOfASimpleCubicLattice) {
  // Simple cubic lattice of touching, slightly overlapping spheres: every particle has
  // exactly 6 contacts along the axes, so chi = 0, all in the ">= 6" bin, and the fabric
  // is phi-weighted identity: F = (1/V) sum_p V_p * 2 e_a e_a = 2 phi per diagonal entry.
  using Exec = Kokkos::DefaultExecutionSpace;
  const int m = 5;
  HostParticles h;
  h.resize(m * m * m);
  for (int i = 0; i < m * m * m; ++i) {
    h.x[i] = i % m + 0.5, h.y[i] = (i / m) % m + 0.5, h.z[i] = i / (m * m) + 0.5;
    h.radius[i] = 0.505, h.density[i] = 1.0;
  }
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.len[d] = m;
  DemParams prm;
  prm.dt = 1e-3, prm.skin = 0.05;
  DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(h), box,
                                          frictionless_linear(1.0, 0.0), prm);
  const Measurements r = sys.measure();
  EXPECT_DOUBLE_EQ(r.z_corrected, 6.0);
  EXPECT_NEAR(r.chi, 0.0, 1e-14);
  EXPECT_DOUBLE_EQ(r.contact_histogram[6], 1.0);
  EXPECT_NEAR(r.fabric[0], 2 * r.phi, 1e-12);
  EXPECT_NEAR(r.fabric[2], 2 * r.phi, 1e-12);
  EXPECT_NEAR(r.fabric[3], 0.0, 1e-12);
  // Stress: each contact carries k delta = 0.01 along a branch (centre distance) of length 1;
  // sigma_xx = (1/V) sum over pairs of l f = (N pairs along x) * 1 * 0.01 / V, no shear.
  EXPECT_NEAR(r.stress[0], m * m * m * 1.0 * 0.01 / box.volume(), 1e-14);
  EXPECT_NEAR(r.stress[3], 0.0, 1e-14);
}

TEST(Measurements, CoordinationChiAndHistogramMatchBruteForceCountOfADensePacking) {
  using Exec = Kokkos::DefaultExecutionSpace;
  PeriodicBox box;
  GasSpec g;
  g.count = 400, g.diameter_min = 1.0, g.diameter_max = 3.0, g.density = 2000, g.phi = 0.4,
  g.seed = 7;
  const HostParticles h = random_gas(g, box);
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.2, prm.damping.translational = 100;
  // Compressed into a contact-rich state below.
  DemSystem<Exec, FrictionlessLinear> sys(Particles<Exec>::from_host(h), box,
                                          frictionless_linear(1e5, 1000), prm);
  sys.set_strain_rate(-2e-2, -2e-2, -2e-2);
  sys.step(2500);
  const Measurements m = sys.measure();
  // Brute force: contacts per particle from all pairs and images.
  auto touching = brute_force(sys.particles(), sys.box(), 0.0);
  const int thr = prm.rattler_threshold;
  double n_r = 0, sum_c = 0, sum_c2 = 0, hist6 = 0, total = 0;
  for (const auto& t : touching) {
    const double c = static_cast<double>(t.size());
    total += c;
    hist6 += c >= 6 ? 1 : 0;
    if (c >= thr) n_r += 1, sum_c += c, sum_c2 += c * c;
  }
  ASSERT_GT(n_r, 100);
  const double zbar = sum_c / n_r;
  EXPECT_NEAR(m.z, total / 400, 1e-12);
  EXPECT_NEAR(m.z_corrected, zbar, 1e-12);
  EXPECT_NEAR(m.rattlers, 400 - n_r, 1e-12);
  const double chi = (sum_c2 / n_r - zbar * zbar) / (zbar * zbar);
  EXPECT_GT(chi, 0.01);  // a disordered packing: the check is not vacuous
  EXPECT_NEAR(m.chi, chi, 1e-12);
  EXPECT_NEAR(m.contact_histogram[6], hist6 / 400, 1e-12);
}
