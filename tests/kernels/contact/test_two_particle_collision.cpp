// Two-particle physics of the linear spring-dashpot: contact duration and restitution
// against the closed forms, momentum conservation, and second-order energy error of the
// undamped collision under velocity Verlet.
#include <gtest/gtest.h>

#include <cmath>

#include "scenarios/collisions/two_particle.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

template <class T>
class TwoParticleTest : public ::testing::Test {};
TYPED_TEST_SUITE(TwoParticleTest, granular::testing::ExecSpaces);

TYPED_TEST(TwoParticleTest, LinearCollisionMatchesClosedFormDurationAndRestitution) {
  const auto model = frictionless_linear(1e5, 1000);
  const double density = 2000;
  for (double d2 : {1.0, 2.0, 3.0}) {
    for (double speed : {0.002, 0.03, 0.1}) {
      CollisionSetup s;
      s.radius1 = 1.0, s.radius2 = 0.5 * d2, s.density = density, s.speed = speed;
      const double m1 = density * 4.0 / 3 * M_PI, m2 = density * M_PI / 6 * d2 * d2 * d2;
      const double m = m1 * m2 / (m1 + m2);
      s.dt = model.normal.contact_duration(m) / 1000;
      const auto r = collide_head_on<TypeParam>(model, s);
      const double tc = model.normal.contact_duration(m), e = model.normal.restitution(m);
      EXPECT_NEAR(r.duration / tc, 1.0, 1e-3) << "d2 " << d2 << " v " << speed;
      EXPECT_NEAR(r.restitution / e, 1.0, 1e-3) << "d2 " << d2 << " v " << speed;
      // Internal forces only: momentum is conserved up to round-off of the sums.
      EXPECT_NEAR(r.momentum_after, r.momentum_before, 1e-12 * std::fabs(r.momentum_before));
    }
  }
}

TYPED_TEST(TwoParticleTest, UndampedCollisionEnergyErrorShrinksAsDtSquared) {
  const auto model = frictionless_linear(1e5, 0.0);
  CollisionSetup s;
  s.radius1 = 1.0, s.radius2 = 0.75, s.density = 2000, s.speed = 0.05;
  const double m1 = 2000 * 4.0 / 3 * M_PI, m2 = m1 * 0.421875;
  const double tc = model.normal.contact_duration(m1 * m2 / (m1 + m2));
  s.dt = tc / 50;
  const auto coarse = collide_head_on<TypeParam>(model, s);
  s.dt = tc / 100;
  const auto fine = collide_head_on<TypeParam>(model, s);
  // Elastic: restitution 1; energy error bounded and second order in dt.
  EXPECT_NEAR(fine.restitution, 1.0, 1e-3);
  EXPECT_GT(coarse.max_energy_error, 1e-6);  // measurable at all
  const double ratio = coarse.max_energy_error / fine.max_energy_error;
  EXPECT_GT(ratio, 3.4) << "coarse " << coarse.max_energy_error << " fine "
                        << fine.max_energy_error;
  EXPECT_LT(ratio, 4.6) << "coarse " << coarse.max_energy_error << " fine "
                        << fine.max_energy_error;
}
