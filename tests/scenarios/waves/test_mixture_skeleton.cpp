// The skeleton measures of a two-species packing (scenarios/waves/mixture_skeleton.hpp) on
// hand-made contact networks whose answers are known: the pressure shares by contact type, the
// contacts per particle by type, and the percolation of the stiff network, which a loop closing
// onto another image of the box makes and a loop inside the box does not.
#include <gtest/gtest.h>

#include <cmath>

#include "scenarios/waves/mixture_skeleton.hpp"

using namespace granular;

namespace {

constexpr int kStiff = 0, kSoft = 1;

void add(ContactNetwork& net, int a, int b, double bx, double by, double bz, double fn) {
  net.i.push_back(a), net.j.push_back(b);
  net.branch.insert(net.branch.end(), {bx, by, bz});
  net.normal_force.push_back(fn);
  net.tangential_force.insert(net.tangential_force.end(), {0.0, 0.0, 0.0});
  net.overlap.push_back(0.01);
}

}  // namespace

// Four stiff particles one unit apart along x in a box 4 long: the contact from the last back
// to the first (its minimum image, one unit on) closes the ring around the box.
TEST(MixtureSkeleton, StiffRingAroundThePeriodicBoxWrapsAndAnOpenChainDoesNot) {
  const double len[3] = {4, 10, 10};
  const std::vector<int> species = {kStiff, kStiff, kStiff, kStiff, kSoft};
  const std::vector<double> x = {0.5, 5, 5, 1.5, 5, 5, 2.5, 5, 5, 3.5, 5, 5, 2, 8, 5};
  ContactNetwork chain;
  add(chain, 0, 1, 1, 0, 0, 1.0);
  add(chain, 1, 2, 1, 0, 0, 1.0);
  add(chain, 2, 3, 1, 0, 0, 1.0);
  const Skeleton open = measure_skeleton(chain, species, x, len, kStiff);
  EXPECT_EQ(open.wrapping_axes, 0);
  EXPECT_DOUBLE_EQ(open.largest_cluster, 1.0);
  ContactNetwork ring = chain;
  add(ring, 0, 3, -1, 0, 0, 1.0);  // from 0 at x = 0.5 to 3 at x = 3.5 through the boundary
  const Skeleton closed = measure_skeleton(ring, species, x, len, kStiff);
  EXPECT_EQ(closed.wrapping_axes, 1);
  EXPECT_DOUBLE_EQ(closed.z_stiff_stiff, 2.0);
  EXPECT_DOUBLE_EQ(closed.z_soft_soft, 0.0);
}

// A square of four stiff contacts inside the box closes onto the same image: no wrapping. Two
// separate stiff pairs make the largest cluster half of the stiff particles.
TEST(MixtureSkeleton, LoopInsideTheBoxDoesNotWrapAndTheLargestClusterIsCounted) {
  const double len[3] = {10, 10, 10};
  const std::vector<int> species(8, kStiff);
  const std::vector<double> x = {1, 1, 1, 2, 1, 1, 2, 2, 1, 1, 2, 1,
                                 5, 5, 5, 6, 5, 5, 8, 8, 8, 8, 9, 8};
  ContactNetwork net;
  add(net, 0, 1, 1, 0, 0, 1.0);
  add(net, 1, 2, 0, 1, 0, 1.0);
  add(net, 2, 3, -1, 0, 0, 1.0);
  add(net, 0, 3, 0, 1, 0, 1.0);
  add(net, 4, 5, 1, 0, 0, 1.0);
  add(net, 6, 7, 0, 1, 0, 1.0);
  const Skeleton s = measure_skeleton(net, species, x, len, kStiff);
  EXPECT_EQ(s.wrapping_axes, 0);
  EXPECT_DOUBLE_EQ(s.largest_cluster, 0.5);
  EXPECT_TRUE(std::isnan(s.z_soft_stiff));  // no soft particles
}

// Shares are normal force times centre distance by type; contacts per particle count both
// ends of a like pair and one end of an unlike pair on each side.
TEST(MixtureSkeleton, PressureSharesAndContactsPerParticleByType) {
  const double len[3] = {10, 10, 10};
  const std::vector<int> species = {kStiff, kStiff, kSoft, kSoft};
  const std::vector<double> x = {1, 1, 1, 3, 1, 1, 1, 3, 1, 3, 3, 1};
  ContactNetwork net;
  add(net, 0, 1, 2, 0, 0, 3.0);  // stiff-stiff: 3 x 2 = 6
  add(net, 0, 2, 0, 2, 0, 1.0);  // stiff-soft: 1 x 2 = 2
  add(net, 1, 3, 0, 2, 0, 0.5);  // stiff-soft: 0.5 x 2 = 1
  add(net, 2, 3, 2, 0, 0, 1.5);  // soft-soft: 1.5 x 2 = 3
  const Skeleton s = measure_skeleton(net, species, x, len, kStiff);
  EXPECT_DOUBLE_EQ(s.share[0], 0.5);
  EXPECT_DOUBLE_EQ(s.share[1], 0.25);
  EXPECT_DOUBLE_EQ(s.share[2], 0.25);
  EXPECT_EQ(s.contacts[0], 1);
  EXPECT_EQ(s.contacts[1], 2);
  EXPECT_EQ(s.contacts[2], 1);
  EXPECT_DOUBLE_EQ(s.z_stiff_stiff, 1.0);
  EXPECT_DOUBLE_EQ(s.z_stiff_soft, 1.0);
  EXPECT_DOUBLE_EQ(s.z_soft_stiff, 1.0);
  EXPECT_DOUBLE_EQ(s.z_soft_soft, 1.0);
}
