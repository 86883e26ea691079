// The one-pass force kernel of host backends (the owner of a contact scatters the reaction
// to its partner; threads take slabs of the neighbour list three apart) against the two-pass
// kernel that devices and multi-contact laws use: the same trajectories to round-off for a
// compressed frictional packing with rolling springs; and the slab partition's invariants
// that make the scattered writes race-free (every particle in one slab, every listed pair
// within adjacent slabs, a slab count the three rounds can colour). And the two-pass kernel's
// two thread mappings (a thread per contact, a thread per particle), and its apart contacts
// flagged (rows left unwritten and unread) or written as zero rows: the same bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::bitwise_equal;

namespace {

using RollingModel = ContactModel<LinearNormal, CoulombTangential, RollingTorsion>;

RollingModel rolling_model() {
  return {LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.5),
          RollingTorsion::uniform({2e4, 50, 0.1, 2e4, 50, 0.1})};
}

HostParticles small_gas(PeriodicBox& box, int count, double phi) {
  GasSpec g;
  g.count = count, g.diameter_min = 1, g.diameter_max = 1.4, g.density = 2000, g.phi = phi;
  g.speed = 0.01, g.seed = 5;
  return random_gas(g, box);
}

template <class Exec>
std::vector<double> host_copy(const typename Particles<Exec>::vec_view& v) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  return std::vector<double>(h.data(), h.data() + h.size());
}

double max_abs(const std::vector<double>& a) {
  double m = 0;
  for (double x : a) m = std::max(m, std::fabs(x));
  return m;
}
double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0;
  for (size_t k = 0; k < a.size(); ++k) m = std::max(m, std::fabs(a[k] - b[k]));
  return m;
}

// The two-pass kernel's comparisons: a damped gas compressed to phi ~ 0.65 (with
// set_strain_rate), through several neighbour rebuilds.
DemParams two_pass_params() {
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.1, prm.damping.translational = 100;
  prm.damping.rotational = 20;
  prm.two_pass_forces = true;
  return prm;
}

}  // namespace

template <class T>
class SlabForcesTest : public ::testing::Test {};
TYPED_TEST_SUITE(SlabForcesTest, granular::testing::ExecSpaces);

TYPED_TEST(SlabForcesTest, OnePassAndTwoPassKernelsGiveTheSameTrajectoryToRoundOff) {
  using Exec = TypeParam;
  if constexpr (!forces_by_slabs<Exec>()) {
    GTEST_SKIP() << "a device runs the two-pass kernel only";
  } else {
    PeriodicBox box;
    const HostParticles h = small_gas(box, 2500, 0.35);
    DemParams prm;
    prm.dt = 0.004, prm.skin = 0.1, prm.damping.translational = 100;
    prm.damping.rotational = 20;
    DemParams two = prm;
    two.two_pass_forces = true;
    DemParams thin = prm;  // another partition: nine slabs, blocks of one cell row
    thin.force_slabs = 9, thin.cell_block_rows = 1;
    DemSystem<Exec, RollingModel> a(Particles<Exec>::from_host(h), box, rolling_model(), prm);
    DemSystem<Exec, RollingModel> b(Particles<Exec>::from_host(h), box, rolling_model(), two);
    DemSystem<Exec, RollingModel> c(Particles<Exec>::from_host(h), box, rolling_model(), thin);
    ASSERT_GE(a.neighbor_list().num_slabs(), 6) << "the packing must span several slab rounds";
    ASSERT_EQ(c.neighbor_list().num_slabs(), 9);
    a.set_strain_rate(-3e-2, -3e-2, -3e-2);  // to phi ~ 0.65: a loaded, frictional packing
    b.set_strain_rate(-3e-2, -3e-2, -3e-2);
    c.set_strain_rate(-3e-2, -3e-2, -3e-2);
    a.step(1800);
    b.step(1800);
    c.step(1800);
    const Measurements m = a.measure();
    ASSERT_GT(m.contacts, a.particles().n) << "too few contacts for the comparison to bite";
    ASSERT_GT(a.neighbor_list().builds(), 2) << "the histories must survive rebuilds";
    // Only the order of the force sums differs: differences of a few ulps per step, grown by
    // the dynamics over 1800 steps, against forces of order one (a wrong or missing
    // reaction term would differ by the force itself).
    const auto fa = host_copy<Exec>(a.particles().f), fb = host_copy<Exec>(b.particles().f);
    const auto qa = host_copy<Exec>(a.particles().torque);
    const auto qb = host_copy<Exec>(b.particles().torque);
    EXPECT_LT(max_abs_diff(fa, fb), 1e-9 * max_abs(fa));
    EXPECT_LT(max_abs_diff(qa, qb), 1e-9 * max_abs(qa));
    EXPECT_LT(max_abs_diff(host_copy<Exec>(a.particles().x), host_copy<Exec>(b.particles().x)),
              1e-12 * box.len[0]);
    EXPECT_GT(max_abs(qa), 0.0);
    const Measurements n = b.measure();
    EXPECT_NEAR(m.pressure, n.pressure, 1e-9 * std::fabs(m.pressure));
    EXPECT_EQ(m.contacts, n.contacts);
    // The partition orders the sums (and the particles) differently, nothing else.
    const Measurements mc = c.measure();
    EXPECT_NEAR(mc.pressure, n.pressure, 1e-9 * std::fabs(n.pressure));
    EXPECT_EQ(mc.contacts, n.contacts);
    EXPECT_NEAR(mc.ekin, n.ekin, 1e-9 * n.ekin);
  }
}

TYPED_TEST(SlabForcesTest, TwoPassKernelGivesTheSameBitsWithAThreadPerContactOrPerParticle) {
  using Exec = TypeParam;
  PeriodicBox box;
  const HostParticles h = small_gas(box, 2500, 0.35);
  const DemParams prm = two_pass_params();
  DemParams per_particle = prm;
  per_particle.contact_thread_per_particle = true;
  DemSystem<Exec, RollingModel> a(Particles<Exec>::from_host(h), box, rolling_model(), prm);
  DemSystem<Exec, RollingModel> b(Particles<Exec>::from_host(h), box, rolling_model(),
                                  per_particle);
  a.set_strain_rate(-3e-2, -3e-2, -3e-2);  // to phi ~ 0.65, with rebuilds on the way
  b.set_strain_rate(-3e-2, -3e-2, -3e-2);
  a.step(1800);
  b.step(1800);
  ASSERT_GT(a.measure().contacts, a.particles().n) << "too few contacts for the comparison";
  ASSERT_GT(a.neighbor_list().builds(), 2);
  // Every contact is evaluated with the same arithmetic and summed in the same order.
  EXPECT_EQ(host_copy<Exec>(a.particles().f), host_copy<Exec>(b.particles().f));
  EXPECT_EQ(host_copy<Exec>(a.particles().torque), host_copy<Exec>(b.particles().torque));
  EXPECT_EQ(host_copy<Exec>(a.particles().x), host_copy<Exec>(b.particles().x));
  EXPECT_EQ(host_copy<Exec>(a.particles().w), host_copy<Exec>(b.particles().w));
  EXPECT_GT(max_abs(host_copy<Exec>(a.particles().torque)), 0.0);
}

namespace {

// Two-pass kernel with flagged apart rows (a), zero rows (b), and the two in turn every
// 150 steps (c): the same bits of forces, torques, positions and spins after compression
// through several rebuilds (laws with rotations: the others' rows are never flagged).
template <class Exec, class Model>
void compare_flagged_and_zero_rows(const Model& model) {
  PeriodicBox box;
  const HostParticles h = small_gas(box, 2500, 0.35);
  const DemParams prm = two_pass_params();
  DemParams zero = prm;
  zero.flag_apart_rows = false;
  DemSystem<Exec, Model> a(Particles<Exec>::from_host(h), box, model, prm);
  DemSystem<Exec, Model> b(Particles<Exec>::from_host(h), box, model, zero);
  DemSystem<Exec, Model> c(Particles<Exec>::from_host(h), box, model, prm);
  for (auto* s : {&a, &b, &c}) s->set_strain_rate(-3e-2, -3e-2, -3e-2);  // to phi ~ 0.65
  a.step(1800);
  b.step(1800);
  for (int k = 0; k < 12; ++k) {
    c.set_flag_apart_rows(k % 2 == 1);
    c.step(150);
  }
  const long contacts = a.measure().contacts;
  ASSERT_GT(contacts, a.particles().n) << "too few contacts for the comparison";
  ASSERT_GT(a.neighbor_list().builds(), 2);
  // Rows the flags skip: listed pairs that are apart (a tenth of the list at least).
  ASSERT_GT(a.neighbor_list().num_pairs(), contacts + contacts / 10);
  for (auto* s : {&b, &c}) {
    EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().f), host_copy<Exec>(s->particles().f)));
    EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().torque),
                              host_copy<Exec>(s->particles().torque)));
    EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().x), host_copy<Exec>(s->particles().x)));
    EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().w), host_copy<Exec>(s->particles().w)));
  }
}

}  // namespace

TYPED_TEST(SlabForcesTest, TwoPassKernelGivesTheSameBitsWithFlaggedApartRowsOrZeroRows) {
  compare_flagged_and_zero_rows<TypeParam>(rolling_model());
  compare_flagged_and_zero_rows<TypeParam>(ContactModel<LinearNormal, CoulombTangential>{
      LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.5), {}});
}

TYPED_TEST(SlabForcesTest, SlabsPartitionTheParticlesAndEveryListedPairJoinsAdjacentSlabs) {
  using Exec = TypeParam;
  for (const bool periodic_z : {true, false}) {
    PeriodicBox box;
    const HostParticles h = small_gas(box, 3000, 0.35);
    box.periodic[2] = periodic_z;  // a walled axis: no wrap between first and last slab
    auto p = Particles<Exec>::from_host(h);
    NeighborList<Exec> nl(0.2);
    nl.build(p, box);
    const int slabs = nl.num_slabs();
    ASSERT_GE(slabs, 6);
    if (periodic_z) {
      EXPECT_EQ(slabs % 3, 0) << "three rounds cannot colour a ring of slabs";
    }
    const auto hs = Kokkos::HostSpace();
    auto begin = Kokkos::create_mirror_view_and_copy(hs, nl.slab_begin());
    auto order = Kokkos::create_mirror_view_and_copy(hs, nl.cell_order());
    auto off = Kokkos::create_mirror_view_and_copy(hs, nl.offsets());
    auto nb = Kokkos::create_mirror_view_and_copy(hs, nl.neighbors());
    ASSERT_EQ(begin(0), 0);
    ASSERT_EQ(begin(slabs), p.n);
    std::vector<int> slab_of(p.n, -1);
    for (int s = 0; s < slabs; ++s) {
      ASSERT_LT(begin(s), begin(s + 1)) << "empty slab " << s;
      for (int q = begin(s); q < begin(s + 1); ++q) {
        ASSERT_EQ(slab_of[order(q)], -1) << "particle in two slabs";
        slab_of[order(q)] = s;
      }
    }
    long pairs = 0, across = 0;
    for (int i = 0; i < p.n; ++i) {
      ASSERT_GE(slab_of[i], 0) << "particle in no slab";
      for (int k = off(i); k < off(i + 1); ++k) {
        const int d = std::abs(slab_of[i] - slab_of[nb(k)]);
        const int gap = periodic_z ? std::min(d, slabs - d) : d;
        EXPECT_LE(gap, 1) << "pair " << i << "-" << nb(k) << " spans slabs " << slab_of[i]
                          << " and " << slab_of[nb(k)];
        ++pairs, across += gap == 1;
      }
    }
    EXPECT_GT(across, 0) << "no pair crosses a slab face: the check is vacuous";
    EXPECT_GT(pairs, static_cast<long>(p.n));
  }
}

// A count asked for by the process (granular run --force-slabs) applies where a list has none
// of its own, lowered to what the box can hold (a multiple of 3 on a periodic axis).
TYPED_TEST(SlabForcesTest, ProcessWideSlabCountAppliesWhereAListHasNone) {
  using Exec = TypeParam;
  PeriodicBox box;
  const HostParticles h = small_gas(box, 3000, 0.35);
  auto p = Particles<Exec>::from_host(h);
  const int saved = default_force_slabs();
  NeighborList<Exec> nl(0.2), own(0.2);
  own.set_partition(3, 4);
  default_force_slabs() = 10;  // no multiple of 3: lowered to 9 on the periodic axis
  nl.build(p, box);
  own.build(p, box);
  default_force_slabs() = saved;
  EXPECT_EQ(nl.num_slabs(), 9);
  EXPECT_EQ(own.num_slabs(), 3);
  NeighborList<Exec> plain(0.2);
  plain.build(p, box);
  EXPECT_EQ(plain.num_slabs(), saved);
}
