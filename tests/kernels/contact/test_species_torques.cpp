// Torques between unlike species. A tangential force f_t at the contact point (mid-overlap)
// acts on i with lever l_i = a_i - delta/2 and on j with l_j = a_j - delta/2, so
// |q_i| = l_i |f_t|, |q_j| = l_j |f_t|, and because l_i + l_j = |r_i - r_j| the total moment
// r_i x f + r_j x (-f) + q_i + q_j vanishes: orbital plus spin angular momentum is conserved.
// The spring, dashpot, friction and rolling parameters are those of the species pair
// (an explicit pair-table entry, different from either like pair).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "kernels/contact/contact_model.hpp"
#include "kernels/contact/species_mixing.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/collisions/two_particle.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

namespace {

using Model = ContactModel<LinearNormal, CoulombTangential, RollingTorsion>;
using TP = CoulombTangential::Params;
using NP = LinearNormal::Params;
using RP = RollingTorsion::Params;

// Species 0 and 1 with their own parameters, and an explicit (0, 1) pair entry whose values
// differ from both like pairs and from their mixed value.
Model two_species_model(double mu01) {
  const TP t0{8e4, 200, 0.5, 0.5}, t1{2e4, 50, 0.2, 0.2};
  const TP t01{5e4, 120, mu01, mu01};
  const auto tangential = pair_table<TP>({t0, t1}, {{std::nullopt, t01}});
  const auto normal = pair_table<NP>({NP{1e5, 300}, NP{3e5, 500}});
  PairTable<RP> rolling = PairTable<RP>::uniform(RP{1e4, 5, 0.1, 2e4, 3, 0.05});
  rolling.p[0][1] = rolling.p[1][0] = RP{3e3, 2, 0.3, 6e3, 1, 0.2};
  return {{normal}, {tangential}, {rolling}};
}

void cross(const double a[3], const double b[3], double c[3]) { cross3(a, b, c); }
double norm(const double a[3]) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

// The pair state of spheres at ri (radius ai, species si) and rj (aj, sj) with relative
// contact-point velocity vt (made tangential here) and relative spin wrel.
PairState state(const double ri[3], double ai, int si, const double rj[3], double aj, int sj,
                const double v[3], const double wrel[3]) {
  PairState s{};
  double d[3];
  for (int k = 0; k < 3; ++k) d[k] = ri[k] - rj[k];
  const double r = norm(d);
  for (int k = 0; k < 3; ++k) s.n[k] = d[k] / r;
  s.delta = ai + aj - r, s.delta_dot = 0;
  s.ai = ai, s.aj = aj, s.mstar = 1.0, s.si = si, s.sj = sj, s.wall = false;
  const double vn = dot3(v, s.n);
  for (int k = 0; k < 3; ++k) s.vt[k] = v[k] - vn * s.n[k], s.wrel[k] = wrel[k];
  return s;
}

}  // namespace

TEST(SpeciesTorques, UnlikePairUsesPairTableAndTorquesBalanceAboutAnyPoint) {
  const double ai = 1.0, aj = 0.45, delta = 4e-3, dt = 1e-3;
  const double u[3] = {1.0, 2.0, -0.5};  // line of centres, not along an axis
  const double un = norm(u);
  const double ri[3] = {0.3, 0.2, -0.1};
  double rj[3];
  for (int k = 0; k < 3; ++k) rj[k] = ri[k] - (ai + aj - delta) * u[k] / un;
  const double v[3] = {2e-3, -1e-3, 3e-3}, wrel[3] = {4e-3, -2e-3, 1e-3};
  const double inf = std::numeric_limits<double>::infinity();
  const Model model = two_species_model(inf);  // sticking: the spring and dashpot are seen
  const PairState s = state(ri, ai, 0, rj, aj, 1, v, wrel);
  ASSERT_NEAR(s.delta, delta, 1e-14);
  double h[Model::history] = {};
  PairForce out;
  model.evaluate(s, dt, h, out);

  // The tangential force from the (0, 1) entry: f_t = -k_t01 v_t dt - g_t01 v_t.
  const double vt_mag = norm(s.vt), ft_mag = (5e4 * dt + 120) * vt_mag;
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(out.ft[k], -(5e4 * dt + 120) * s.vt[k], 1e-13 * ft_mag) << k;
  EXPECT_NEAR(out.fn, 1e5 * 3e5 / (1e5 + 3e5) * 2 * delta, 1e-13 * out.fn);  // mixed k_n

  // Swapping the species order changes nothing: the table is symmetric.
  {
    double h2[Model::history] = {};
    PairForce o2;
    model.evaluate(state(ri, ai, 1, rj, aj, 0, v, wrel), dt, h2, o2);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(o2.ft[k], out.ft[k]);
  }

  // Levers: the tangential torques have magnitudes l_i |f_t| and l_j |f_t|. Remove the
  // rolling/torsion torques (equal and opposite) by evaluating without them.
  {
    Model no_roll = model;
    no_roll.rolling.table = PairTable<RP>::uniform(RP{0, 0, inf, 0, 0, inf});
    double h3[Model::history] = {};
    PairForce o3;
    no_roll.evaluate(s, dt, h3, o3);
    EXPECT_NEAR(norm(o3.q), (ai - 0.5 * delta) * ft_mag, 1e-13 * ft_mag);
    EXPECT_NEAR(norm(o3.qj), (aj - 0.5 * delta) * ft_mag, 1e-13 * ft_mag);
    // Both torques turn the spheres the same way for a tangential force (gear-like), and
    // they are perpendicular to the normal and to the force.
    EXPECT_NEAR(dot3(o3.q, s.n), 0.0, 1e-13 * ft_mag);
    EXPECT_NEAR(dot3(o3.q, o3.ft), 0.0, 1e-13 * ft_mag * ft_mag);
    EXPECT_GT(dot3(o3.q, o3.qj), 0.0);
  }

  // Rolling and torsion from the (0, 1) entry: one step of the spring plus dashpot.
  {
    const double ar = ai * aj / (ai + aj);
    double q_roll[3], wr[3];
    cross(wrel, s.n, wr);  // (w_i - w_j) x n
    double nxw[3];
    cross(s.n, wr, nxw);  // n x (w x n) = tangential part of w
    const double wn = dot3(wrel, s.n);
    for (int k = 0; k < 3; ++k)
      q_roll[k] = -ar * ar * ((3e3 * dt + 2) * nxw[k] + (6e3 * dt + 1) * wn * s.n[k]);
    const double scale = norm(q_roll);
    // Total torque on i minus the tangential part (-l_i n x f_t) is the rolling torque.
    double nxf[3];
    cross(s.n, out.ft, nxf);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(out.q[k] + (ai - 0.5 * delta) * nxf[k], q_roll[k], 1e-12 * scale) << k;
  }

  // Total moment about the origin (and hence about any point, the forces summing to zero).
  double m[3], c[3], fj[3];
  for (int k = 0; k < 3; ++k) fj[k] = -out.f[k];
  cross(ri, out.f, m);
  cross(rj, fj, c);
  for (int k = 0; k < 3; ++k) m[k] += c[k] + out.q[k] + out.qj[k];
  // Each term is at most ~|r| |f|; the residual is round-off of those terms.
  const double scale = (norm(ri) + norm(rj) + ai) * norm(out.f);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(m[k], 0.0, 1e-14 * scale) << k;
}

TEST(SpeciesTorques, UnlikePairSlidesAtPairFrictionCoefficient) {
  const double ai = 1.0, aj = 0.45, delta = 4e-3, dt = 1e-3, mu01 = 0.05;
  const double ri[3] = {0, 0, 0}, rj[3] = {-(ai + aj - delta), 0, 0};
  const double v[3] = {0, 0.5, 0}, w[3] = {0, 0, 0};
  const Model model = two_species_model(mu01);
  double h[Model::history] = {};
  PairForce out;
  model.evaluate(state(ri, ai, 0, rj, aj, 1, v, w), dt, h, out);
  // Trial force (5e4 dt + 120) 0.5 = 85 exceeds mu01 f_n = 0.05 * 600 = 30: slides at mu01,
  // not at either species' own coefficient (0.5, 0.2) nor their mix.
  ASSERT_GT((5e4 * dt + 120) * 0.5, 2 * mu01 * out.fn);
  EXPECT_NEAR(norm(out.ft), mu01 * out.fn, 1e-14 * out.fn);
  EXPECT_NEAR(norm(out.q), (ai - 0.5 * delta) * mu01 * out.fn, 1e-14 * out.fn);
  EXPECT_NEAR(norm(out.qj), (aj - 0.5 * delta) * mu01 * out.fn, 1e-14 * out.fn);
}

template <class T>
class SpeciesTorqueDynamics : public ::testing::Test {};
TYPED_TEST_SUITE(SpeciesTorqueDynamics, granular::testing::ExecSpaces);

TYPED_TEST(SpeciesTorqueDynamics, UnlikeSpinningCollisionConservesTotalAngularMomentum) {
  // Oblique, spinning impact between species 0 (radius 1) and 1 (radius 0.45) with friction
  // (sliding, then sticking), rolling and torsion resistance from the pair entry: no external
  // torque, so angular momentum about the centre of mass (orbital + spin) is conserved.
  CollisionSetup s;
  s.radius1 = 1.0, s.radius2 = 0.45, s.density = 2000, s.speed = 0.01;
  s.tangential_speed = 0.004, s.spin = 0.02, s.species1 = 0, s.species2 = 1;
  const Model model = two_species_model(0.3);
  const double m1 = 2000 * 4.0 / 3.0 * M_PI, m2 = m1 * 0.45 * 0.45 * 0.45;
  s.dt = model.normal.contact_duration(m1 * m2 / (m1 + m2), 0, 1) / 2000;
  const CollisionResult r = collide_head_on<TypeParam>(model, s);
  EXPECT_GT(r.duration, 0.0);
  EXPECT_NE(r.slip_after, r.slip_before);  // the tangential law acted
  double scale = 0;
  for (int d = 0; d < 3; ++d) scale = std::max(scale, std::fabs(r.angular_momentum_before[d]));
  // Verlet conserves angular momentum exactly for balanced torques; what remains is the
  // round-off of ~10^4 steps on O(scale) terms.
  for (int d = 0; d < 3; ++d)
    EXPECT_NEAR(r.angular_momentum_after[d], r.angular_momentum_before[d], 1e-11 * scale) << d;
}
