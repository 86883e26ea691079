// Frictional contact physics: oblique collisions in the sliding regime (tangential impulse
// = mu x normal impulse), in the sticking regime (the tangential spring is a harmonic
// oscillator of reduced tangential mass 2/7 m*), angular momentum about the centre of
// mass, and contact history that survives neighbour-list rebuilds unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "kernels/dem/dem_system.hpp"
#include "scenarios/collisions/two_particle.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

namespace {
using Frictional = ContactModel<LinearNormal, CoulombTangential>;

Frictional frictional(double kn, double gn, double kt, double gt, double mu) {
  return {LinearNormal::uniform(kn, gn), CoulombTangential::uniform(kt, gt, mu, mu), {}};
}

double mass(double a) { return 2000.0 * 4.0 / 3.0 * M_PI * a * a * a; }

void expect_angular_momentum_conserved(const CollisionResult& r) {
  double scale = 0;
  for (int d = 0; d < 3; ++d) scale = std::max(scale, std::fabs(r.angular_momentum_before[d]));
  for (int d = 0; d < 3; ++d)
    EXPECT_NEAR(r.angular_momentum_after[d], r.angular_momentum_before[d], 1e-11 * scale) << d;
}
}  // namespace

template <class T>
class FrictionTest : public ::testing::Test {};
TYPED_TEST_SUITE(FrictionTest, granular::testing::ExecSpaces);

TYPED_TEST(FrictionTest, SlidingObliqueCollisionTransfersMuTimesNormalImpulse) {
  const double mu = 0.1, vn = 0.001;
  CollisionSetup s;
  s.radius1 = 1.0, s.radius2 = 0.7, s.density = 2000, s.speed = vn;
  // Slip from spin, not from sliding centres, so the line of centres barely turns.
  s.spin = 25 * mu * vn / 1.0;
  s.record = true;
  const double m = mass(1.0) * mass(0.7) / (mass(1.0) + mass(0.7));
  for (double gn : {0.0, 600.0}) {
    const auto model = frictional(1e5, gn, 8e4, 0.0, mu);
    s.dt = model.normal.contact_duration(m) / 1000;
    const auto r = collide_head_on<TypeParam>(model, s);
    ASSERT_GT(r.slip_after, 0.0) << "the contact stopped sliding: the test premise fails";
    // Sliding at every sample: |f_t| = mu |f_n| to round-off.
    double jn = 0, jt = 0;
    for (size_t k = 0; k < r.force_normal.size(); ++k) {
      EXPECT_NEAR(r.force_tangential[k], mu * std::fabs(r.force_normal[k]),
                  1e-12 * std::fabs(r.force_normal[k]) + 1e-300);
      jn += r.force_normal[k] * s.dt;  // Verlet applies each force sample for exactly dt
      jt += r.force_tangential[k] * s.dt;
    }
    // The tangential velocity change of the centres equals mu (1 + e) v_n when the normal
    // force never turns tensile (undamped); with damping the friction limit uses |f_n| and
    // the transfer can only exceed that.
    const double dvt = std::fabs(r.vy_rel_after - r.vy_rel_before);
    EXPECT_NEAR(jn / m, (1 + r.restitution) * vn, 2e-3 * vn);
    if (gn == 0.0) {
      EXPECT_NEAR(dvt, mu * (1 + r.restitution) * vn, 2e-3 * dvt);
    } else {
      EXPECT_GE(dvt, mu * (1 + r.restitution) * vn * (1 - 2e-3));
      EXPECT_LT(r.restitution, 0.99);
    }
    EXPECT_NEAR(dvt, jt / m, 2e-3 * dvt);
    expect_angular_momentum_conserved(r);
  }
}

TYPED_TEST(FrictionTest, StickingObliqueCollisionFollowsTangentialOscillator) {
  const double inf = std::numeric_limits<double>::infinity();
  const double kt = 4e4;
  const auto model = frictional(1e5, 800.0, kt, 0.0, inf);
  CollisionSetup s;
  s.radius1 = 1.0, s.radius2 = 1.0, s.density = 2000, s.speed = 1e-3, s.spin = 4e-4;
  const double m = 0.5 * mass(1.0);
  const double tc = model.normal.contact_duration(m);
  s.dt = tc / 2000;
  const auto r = collide_head_on<TypeParam>(model, s);
  // Sticking: the slip u obeys m_t du/dt = -k_t xi with m_t = m* / (1 + m* sum a^2/I) = 2/7 m*
  // for equal spheres, so u(t_c) = u0 cos(w_t t_c), independent of the normal law.
  const double wt = std::sqrt(kt / (2.0 / 7.0 * m));
  EXPECT_NEAR(r.slip_after / r.slip_before, std::cos(wt * tc), 2e-3);
  EXPECT_NEAR(r.duration / tc, 1.0, 1e-3);
  expect_angular_momentum_conserved(r);
}

namespace {
template <class Exec>
std::vector<double> frictional_run(long rebuild_every, long& builds, double& tangential_stress) {
  GasSpec g;
  g.count = 500, g.diameter_min = 1, g.diameter_max = 3, g.density = 2000, g.phi = 0.45;
  g.speed = 0.01, g.seed = 9;
  PeriodicBox box;
  const HostParticles h = random_gas(g, box);
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.2, prm.damping.translational = 50, prm.damping.rotational = 10;
  prm.rebuild_every = rebuild_every;
  DemSystem<Exec, Frictional> sys(Particles<Exec>::from_host(h), box,
                                  frictional(1e5, 1000, 8e4, 200, 0.5), prm);
  sys.set_strain_rate(-8e-3, -8e-3, -8e-3);  // into a dense, sliding, rotating packing
  sys.step(3000);
  builds = sys.neighbor_list().builds();
  const Measurements m = sys.measure();
  tangential_stress = std::fabs(m.stress_tangential[0]) + std::fabs(m.stress_tangential[3]);
  // By particle identity: the two runs keep the particles in different memory orders.
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
  auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().w);
  auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().id);
  std::vector<double> out(6 * x.extent(0));
  for (size_t i = 0; i < x.extent(0); ++i)
    for (int d = 0; d < 3; ++d) out[6 * id(i) + d] = x(i, d), out[6 * id(i) + 3 + d] = w(i, d);
  return out;
}
}  // namespace

TYPED_TEST(FrictionTest, HistorySurvivesRebuildsEveryStepOrBySkinIdentically) {
  long builds_every = 0, builds_skin = 0;
  double ts_every = 0, ts_skin = 0;
  const auto every = frictional_run<TypeParam>(1, builds_every, ts_every);
  const auto skin = frictional_run<TypeParam>(0, builds_skin, ts_skin);
  EXPECT_GT(builds_every, 2999);
  EXPECT_GT(builds_skin, 3);
  EXPECT_LT(builds_skin, builds_every / 10);
  EXPECT_GT(ts_skin, 0.0);  // tangential springs carry load: the history matters
  ASSERT_EQ(every.size(), skin.size());
  // Only the summation order of forces can differ (partners may sit in other cells), so
  // the runs agree to round-off amplified over 3000 steps, far below any physical scale.
  double worst = 0;
  for (size_t k = 0; k < every.size(); ++k) worst = std::max(worst, std::fabs(every[k] - skin[k]));
  EXPECT_LT(worst, 1e-9);
}

TYPED_TEST(FrictionTest, DampedFrictionalCollisionLosesTheDissipatedWork) {
  // Oblique, spinning impact with normal and tangential dashpots and Coulomb sliding: the
  // kinetic energy (translational + rotational) lost equals the work of the normal dashpot
  // plus that of the tangential force on the slip (friction + tangential dashpot), up to
  // the bookkeeping's quadrature error, which is first order in dt (forces are sampled
  // once per step): it must halve when dt halves.
  const double gn = 200, mu = 0.3;
  const auto model = frictional(1e5, gn, 8e4, 100.0, mu);
  CollisionSetup s;
  s.radius1 = 1.0, s.radius2 = 0.8, s.density = 2000, s.speed = 0.01;
  s.tangential_speed = 0.012, s.spin = -0.008, s.record = true, s.gamma_n = gn;
  const double m = mass(1.0) * mass(0.8) / (mass(1.0) + mass(0.8));
  double mismatch[2];
  for (int level = 0; level < 2; ++level) {
    s.dt = model.normal.contact_duration(m) / (4000 << level);
    const auto r = collide_head_on<TypeParam>(model, s);
    const double lost = r.ekin_before - r.ekin_after;
    EXPECT_GT(r.dissipated_normal, 0.2 * lost);  // both mechanisms matter here
    EXPECT_GT(r.dissipated_tangential, 0.2 * lost);
    mismatch[level] = (r.dissipated_normal + r.dissipated_tangential) / lost - 1;
  }
  EXPECT_LT(std::fabs(mismatch[1]), 1e-3);
  EXPECT_NEAR(mismatch[0] / mismatch[1], 2.0, 0.2) << mismatch[0] << " " << mismatch[1];
}
