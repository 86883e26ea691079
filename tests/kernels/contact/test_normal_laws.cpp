// Nonlinear normal laws. Hertz: contact duration 2.87 (m*^2 / (R E*^2 v))^{1/5} over a
// decade of impact speeds and a force that grows as delta^{3/2}. Hysteretic: a scripted
// load-unload-reload path reproduces the piecewise force of the spec at every sample, for
// kc/k2 in {1/20, 1, 20}; with kc = 0 a collision's restitution is sqrt(k1/k2).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "scenarios/collisions/two_particle.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

template <class T>
class NormalLawTest : public ::testing::Test {};
TYPED_TEST_SUITE(NormalLawTest, granular::testing::ExecSpaces);

TYPED_TEST(NormalLawTest, HertzContactDurationFollowsImpactSpeedToTheMinusOneFifth) {
  const double E = 7e4, nu = 0.3;  // N/mm^2
  ContactModel<HertzNormal> model{
      {PairTable<HertzNormal::Params>::uniform(HertzNormal::modulus_form(E, nu, E, nu, 0.0))},
      {},
      {}};
  const double estar = 1.0 / (2 * (1 - nu * nu) / E);
  CollisionSetup s;
  s.radius1 = 1.0, s.radius2 = 0.6, s.density = 2000, s.record = true;
  const double m1 = 2000 * 4.0 / 3 * M_PI, m2 = m1 * 0.216, m = m1 * m2 / (m1 + m2);
  const double R = 0.6 / 1.6;
  for (double v : {0.002, 0.006, 0.02}) {
    s.speed = v;
    const double tc = 2.868 * std::pow(m * m / (R * estar * estar * v), 0.2);
    s.dt = tc / 2000;
    const auto r = collide_head_on<TypeParam>(model, s);
    EXPECT_NEAR(r.duration / tc, 1.0, 0.01) << "v " << v;
    EXPECT_NEAR(r.restitution, 1.0, 1e-3);
    // Force against overlap: exactly (4/3) E* sqrt(R) delta^{3/2} at every contact sample.
    int samples = 0;
    for (size_t k = 0; k < r.delta.size(); ++k) {
      if (r.delta[k] <= 0) continue;
      const double expect = 4.0 / 3.0 * estar * std::sqrt(R) * std::pow(r.delta[k], 1.5);
      EXPECT_NEAR(r.force[k], expect, 1e-9 * expect);
      ++samples;
    }
    EXPECT_GT(samples, 1000);
  }
}

namespace {
// Independent transcription of the spec's hysteretic law as a state machine on delta_max:
// loading branch k1, un/reloading k2 around delta0 = (1 - k1/k2) delta_max, adhesive
// branch -kc delta reached from above moves the reloading line through the current point.
struct ReferenceHysteresis {
  double k1, k2, kc, dmax = 0;
  double operator()(double d) {
    if (d <= 0) return 0.0;
    dmax = std::max(dmax, d);
    const double d0 = (1 - k1 / k2) * dmax;
    const double unload = k2 * (d - d0);
    if (unload >= k1 * d) return k1 * d;
    if (-kc * d >= unload) {
      dmax = d * (k2 + kc) / (k2 - k1);  // the k2 line through (d, -kc d)
      return -kc * d;
    }
    return unload;
  }
};
}  // namespace

TEST(HystereticLaw, ScriptedPathReproducesPiecewiseForceAtEverySample) {
  const double k2 = 15e4, k1 = 0.666 * k2;
  // Load to 1, unload to 0.2, reload to 0.8 (inside the loop), load on to 1.5 (virgin again),
  // unload to 0.005 (through the adhesive branch), reload to 0.6.
  std::vector<double> path;
  auto ramp = [&](double a, double b) {
    for (int k = 0; k <= 2000; ++k) path.push_back(1e-3 * (a + (b - a) * k / 2000.0));
  };
  ramp(0, 1), ramp(1, 0.2), ramp(0.2, 0.8), ramp(0.8, 1.5), ramp(1.5, 0.005), ramp(0.005, 0.6);
  for (double ratio : {1.0 / 20, 1.0, 20.0}) {
    const auto law = HystereticNormal::uniform(k1, k2, ratio * k2, 0.0);
    ReferenceHysteresis ref{k1, k2, ratio * k2};
    double h = 0;
    int adhesive = 0, unloading = 0, loading = 0;
    for (double d : path) {
      PairState s{};
      s.delta = d;
      const double f = law.force(s, &h);
      const double want = ref(d);
      EXPECT_NEAR(f, want, 1e-12 * std::fabs(want) + 1e-300) << "kc/k2 " << ratio << " delta " << d;
      if (d > 0 && std::fabs(f + ratio * k2 * d) < 1e-9 * k2 * d)
        ++adhesive;
      else if (d > 0 && std::fabs(f - k1 * d) < 1e-9 * k1 * d)
        ++loading;
      else
        ++unloading;
    }
    // Every branch is visited, so the comparison covers all switches.
    EXPECT_GT(adhesive, 5) << ratio;
    EXPECT_GT(loading, 100) << ratio;
    EXPECT_GT(unloading, 100) << ratio;
    // delta_min = ((k2 - k1)/(k2 + kc)) delta_max: the most attractive point of the first loop.
    const double dmax = 1.5e-3, dmin = (k2 - k1) / (k2 + ratio * k2) * dmax;
    const double d0 = (1 - k1 / k2) * dmax;
    EXPECT_NEAR(k2 * (dmin - d0), -ratio * k2 * dmin, 1e-9 * k2 * dmin);
  }
}

TYPED_TEST(NormalLawTest, HystereticCollisionWithoutAdhesionRestitutionIsSqrtK1OverK2) {
  const double k2 = 15e4;
  for (double k1_over_k2 : {0.5, 0.666}) {
    ContactModel<HystereticNormal> model{
        HystereticNormal::uniform(k1_over_k2 * k2, k2, 0.0, 0.0), {}, {}};
    CollisionSetup s;
    s.radius1 = 1.0, s.radius2 = 0.8, s.density = 2000, s.speed = 0.01;
    const double m1 = 2000 * 4.0 / 3 * M_PI, m2 = m1 * 0.512, m = m1 * m2 / (m1 + m2);
    s.dt = M_PI * std::sqrt(m / k2) / 2000;
    const auto r = collide_head_on<TypeParam>(model, s);
    EXPECT_NEAR(r.restitution / std::sqrt(k1_over_k2), 1.0, 1e-3);
  }
}
