// Species mixing: pair parameters by the normalised harmonic rule unless a pair table entry
// overrides them, and a two-species collision that follows the mixed stiffness.
#include <gtest/gtest.h>

#include <cmath>

#include "kernels/contact/species_mixing.hpp"
#include "scenarios/collisions/two_particle.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

TEST(SpeciesMixing, UnlikePairsTakeHarmonicMeanAndOverridesWin) {
  const std::vector<LinearNormal::Params> sp = {{1e5, 1000}, {4e3, 10}};
  const auto t = pair_table(sp);
  EXPECT_DOUBLE_EQ(t(0, 0).kn, 1e5);
  EXPECT_DOUBLE_EQ(t(1, 1).kn, 4e3);
  EXPECT_DOUBLE_EQ(t(0, 1).kn, 2 * 1e5 * 4e3 / (1e5 + 4e3));
  EXPECT_DOUBLE_EQ(t(1, 0).gn, 2 * 1000.0 * 10 / 1010);
  std::vector<std::vector<std::optional<LinearNormal::Params>>> over(
      2, std::vector<std::optional<LinearNormal::Params>>(2));
  over[1][0] = LinearNormal::Params{7e3, 5};
  const auto u = pair_table(sp, over);
  EXPECT_DOUBLE_EQ(u(0, 1).kn, 7e3);
  EXPECT_DOUBLE_EQ(u(1, 0).gn, 5.0);
  EXPECT_DOUBLE_EQ(u(0, 0).kn, 1e5);
  // Infinite friction stays infinite when both species have it.
  const double inf = std::numeric_limits<double>::infinity();
  const auto c =
      pair_table(std::vector<CoulombTangential::Params>{{1, 0, inf, inf, 0}, {2, 0, inf, inf, 0}});
  EXPECT_TRUE(std::isinf(c(0, 1).mu_s));
}

// The one mixing rule every pair table uses (kernels' tables, the scenes' and the mixture
// study's materials): an infinite member leaves the finite one's limit, where the kernels'
// copy of the rule gave 2 inf q / inf = NaN; a value paired with itself stays exact, where
// 2pp/(p + p) misses p = 0.1 by an ulp.
TEST(SpeciesMixing, OneRuleForEveryTableWithInfiniteAndEqualMembers) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(mix_pair(PairRule::Harmonic, 3.0, 6.0), 4.0);
  EXPECT_EQ(mix_pair(PairRule::ProductOverSum, 3.0, 6.0), 2.0);
  EXPECT_EQ(mix_pair(PairRule::Harmonic, inf, 0.5), 1.0);
  EXPECT_EQ(mix_pair(PairRule::Harmonic, 0.5, inf), 1.0);
  EXPECT_EQ(mix_pair(PairRule::ProductOverSum, inf, 0.5), 0.5);
  EXPECT_TRUE(std::isinf(mix_pair(PairRule::ProductOverSum, inf, inf)));
  EXPECT_EQ(mix_pair(PairRule::Harmonic, inf, 0.0), 0.0);
  EXPECT_EQ(mix_pair(PairRule::Harmonic, 0.0, 0.0), 0.0);
  EXPECT_NE(2 * 0.1 * 0.1 / (0.1 + 0.1), 0.1);  // why the shortcut matters
  EXPECT_EQ(mix_pair(PairRule::Harmonic, 0.1, 0.1), 0.1);
  // The kernels' tables with a rigid species: K of (rigid, q) is twice q's, not NaN.
  const auto t = pair_table(std::vector<LinearNormal::Params>{{inf, 0.0}, {4e3, 10}});
  EXPECT_EQ(t(0, 1).kn, 8e3);
  EXPECT_EQ(t(0, 1).gn, 0.0);
  EXPECT_EQ(pair_rule_named("product_over_sum"), PairRule::ProductOverSum);
  EXPECT_EQ(pair_rule_named("harmonic"), PairRule::Harmonic);
}

TEST(SpeciesMixing, SoftStiffCollisionLastsTheMixedContactDuration) {
  using Exec = Kokkos::DefaultExecutionSpace;
  const std::vector<LinearNormal::Params> sp = {{1e5, 0}, {2e3, 0}};  // stiff and soft species
  const ContactModel<LinearNormal> model{LinearNormal{pair_table(sp)}, {}, {}};
  CollisionSetup s;
  s.radius1 = 1.0, s.radius2 = 1.0, s.density = 2000, s.speed = 0.01;
  s.species1 = 0, s.species2 = 1;
  const double m = 0.5 * 2000 * 4.0 / 3 * M_PI;
  const double k = 2 * 1e5 * 2e3 / (1e5 + 2e3);
  s.dt = M_PI * std::sqrt(m / k) / 1000;
  const auto r = collide_head_on<Exec>(model, s);
  EXPECT_NEAR(r.duration / (M_PI * std::sqrt(m / k)), 1.0, 1e-3);
}
