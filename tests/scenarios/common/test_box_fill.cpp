// Filling a box: random insertion leaves no overlap (checked against all pairs), keeps
// particles off the walls of walled axes while periodic axes wrap, depends on the seed
// only, and refuses a region too small for the set with a message.
#include <gtest/gtest.h>

#include <cmath>

#include "core/run/error.hpp"
#include "scenarios/common/box_fill.hpp"

using namespace granular;

TEST(BoxFill, InsertedSpheresNeverOverlapAndStayInsideTheWalls) {
  FillSpec f;
  f.count = 400, f.diameter_mean = 1.0, f.diameter_spread = 0.3, f.seed = 7;
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = 9.0;
  box.periodic[2] = false;  // periodic in x and y, walls in z
  for (int d = 0; d < 3; ++d) f.lo[d] = 0, f.hi[d] = 9.0;
  const HostParticles h = fill_region(f, box);
  ASSERT_EQ(h.size(), 400);
  double phi = 0;
  for (int i = 0; i < h.size(); ++i) {
    EXPECT_GE(h.z[i] - h.radius[i], 0.0);
    EXPECT_LE(h.z[i] + h.radius[i], 9.0);
    EXPECT_GE(h.radius[i], 0.35 - 1e-12);
    EXPECT_LE(h.radius[i], 0.65 + 1e-12);
    phi += 4.0 / 3.0 * M_PI * std::pow(h.radius[i], 3) / 729.0;
    for (int j = 0; j < i; ++j) {
      const double dx = box.min_image(h.x[i] - h.x[j], 0), dy = box.min_image(h.y[i] - h.y[j], 1);
      const double dz = h.z[i] - h.z[j], s = h.radius[i] + h.radius[j];
      EXPECT_GE(dx * dx + dy * dy + dz * dz, s * s) << i << " " << j;
    }
  }
  EXPECT_GT(phi, 0.25);  // a dense insertion, where overlaps would show
  const HostParticles again = fill_region(f, box);
  for (int i = 0; i < h.size(); ++i) EXPECT_EQ(h.x[i], again.x[i]);
}

TEST(BoxFill, RegionTooSmallForTheSetIsAnInputError) {
  FillSpec f;
  f.count = 2000, f.diameter_mean = 1.0;
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = 8.0, box.periodic[d] = false;
  for (int d = 0; d < 3; ++d) f.lo[d] = 0, f.hi[d] = 8.0;  // phi would be 2
  EXPECT_THROW(fill_region(f, box), InputError);
}

TEST(BoxFill, SettlingWaitsForTheMinimumStepsBeforeTrustingTheCriterion) {
  // A criterion that holds from the start (balls inserted at rest) must not end settling
  // before min_steps; one that never holds gives -1 after max_steps.
  long advanced = 0;
  const auto advance = [&](long n) { advanced += n; };
  EXPECT_EQ(settle(
                advance, [] { return true; }, 100, 10000, 2500),
            2500);
  EXPECT_EQ(advanced, 2500);
  advanced = 0;
  EXPECT_EQ(settle(
                advance, [] { return true; }, 100, 10000),
            0);
  EXPECT_EQ(advanced, 0);
  advanced = 0;
  EXPECT_EQ(settle(
                advance, [] { return false; }, 100, 1000, 200),
            -1);
  EXPECT_EQ(advanced, 1000);
}
