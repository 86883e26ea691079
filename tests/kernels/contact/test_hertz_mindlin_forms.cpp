// Hertz normal and Mindlin tangential laws in both parameterisations of docs/model_dem.md §2.2
// and §3, evaluated on a pair held at a known overlap and compared with the formulas:
//   normal, modulus form:    f = (4/3) E* sqrt(R) delta^{3/2},  1/E* = sum (1 - nu^2)/E
//   normal, stiffness form:  f = k_H delta^{3/2},  k_H = (G_p/(1 - nu)) sqrt(dbar)
//   tangential, modulus:     k_t = 8 G* sqrt(R delta),  1/G* = sum (2 - nu)/G
//   tangential, stiffness:   k_t = (2 G_p/(2 - nu)) sqrt(dbar delta)
// with the dashpots alpha sqrt(L delta), the Coulomb cap mu f_n when sliding, and the
// species mixing of the Mindlin modulus form (harmonic mean of 8 G*_ii = 8 G*_ij).
// Every check is a handful of floating-point operations, so tolerances are 1e-13 relative.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "kernels/contact/contact_model.hpp"
#include "kernels/contact/species_mixing.hpp"

using namespace granular;

namespace {

constexpr double kTol = 1e-13;  // relative: a few roundings of O(1) operations

// A pair along x with radii ai, aj, overlap delta and species (si, sj); tangential
// relative velocity vt along y.
PairState pair(double ai, double aj, double delta, double delta_dot = 0, double vt = 0, int si = 0,
               int sj = 0) {
  PairState s{};
  s.n[0] = 1, s.n[1] = 0, s.n[2] = 0;
  s.delta = delta, s.delta_dot = delta_dot;
  s.ai = ai, s.aj = aj, s.mstar = 1.0;
  s.si = si, s.sj = sj, s.wall = false;
  for (int d = 0; d < 3; ++d) s.vt[d] = 0, s.wrel[d] = 0;
  s.vt[1] = vt;
  return s;
}

double estar(double Ei, double nui, double Ej, double nuj) {
  return 1.0 / ((1 - nui * nui) / Ei + (1 - nuj * nuj) / Ej);
}
double gstar(double Gi, double nui, double Gj, double nuj) {
  return 1.0 / ((2 - nui) / Gi + (2 - nuj) / Gj);
}

}  // namespace

TEST(HertzForms, ModulusFormIsFourThirdsEStarSqrtRDeltaToTheThreeHalves) {
  const double Ei = 7e4, nui = 0.2, Ej = 2e5, nuj = 0.3, ai = 1.0, aj = 0.6;
  HertzNormal law{
      PairTable<HertzNormal::Params>::uniform(HertzNormal::modulus_form(Ei, nui, Ej, nuj, 0.0))};
  const double R = ai * aj / (ai + aj), E = estar(Ei, nui, Ej, nuj);
  for (double delta : {1e-5, 1e-4, 1e-3, 1e-2}) {
    const double expected = 4.0 / 3.0 * E * std::sqrt(R) * std::pow(delta, 1.5);
    const PairState s = pair(ai, aj, delta);
    EXPECT_NEAR(law.force(s, nullptr), expected, kTol * expected) << delta;
    EXPECT_NEAR(law.elastic_force(s, nullptr), expected, kTol * expected) << delta;
    // Energy is the integral of the force: (2/5) k delta^{5/2}.
    const double e = 0.4 * 4.0 / 3.0 * E * std::sqrt(R) * std::pow(delta, 2.5);
    EXPECT_NEAR(law.energy(s, nullptr), e, kTol * e) << delta;
  }
}

TEST(HertzForms, StiffnessFormIsKHDeltaToTheThreeHalvesWithPairDiameter) {
  const double Gp = 29e3, nu = 0.2, alpha = 1000, ai = 1.0, aj = 0.6;
  HertzNormal law{
      PairTable<HertzNormal::Params>::uniform(HertzNormal::stiffness_form(Gp, nu, alpha))};
  const double dbar = ai + aj;  // (d_i + d_j)/2: the pair's mean diameter
  const double kH = Gp / (1 - nu) * std::sqrt(dbar);
  for (double delta : {1e-5, 1e-4, 1e-3, 1e-2}) {
    const double ddot = 3e-3;
    const double elastic = kH * std::pow(delta, 1.5);
    const double viscous = alpha * std::sqrt(dbar * delta) * ddot;  // gamma_n^H d(delta)/dt
    const PairState s = pair(ai, aj, delta, ddot);
    EXPECT_NEAR(law.elastic_force(s, nullptr), elastic, kTol * elastic) << delta;
    EXPECT_NEAR(law.force(s, nullptr), elastic + viscous, kTol * (elastic + viscous)) << delta;
  }
  // The exponent itself: quadrupling the overlap multiplies the force by exactly 8.
  const double f1 = law.elastic_force(pair(ai, aj, 1e-3), nullptr);
  const double f4 = law.elastic_force(pair(ai, aj, 4e-3), nullptr);
  EXPECT_NEAR(f4 / f1, 8.0, 8.0 * kTol);
}

TEST(MindlinTangential, ModulusFormStiffnessIsEightGStarSqrtRDelta) {
  const double Gi = 3e4, nui = 0.2, Gj = 8e4, nuj = 0.3, ai = 1.0, aj = 0.6;
  // Per-species coefficient 8 G*_ii; the unlike pair comes from the mixing rule and must
  // equal 8 G*_ij of the two materials.
  using P = CoulombTangential::Params;
  const double inf = std::numeric_limits<double>::infinity();
  const int law = CoulombTangential::MindlinReducedRadius;
  const P pi{8 * gstar(Gi, nui, Gi, nui), 0, inf, inf, law};
  const P pj{8 * gstar(Gj, nuj, Gj, nuj), 0, inf, inf, law};
  const CoulombTangential tangential{pair_table<P>({pi, pj})};
  const double G = gstar(Gi, nui, Gj, nuj), R = ai * aj / (ai + aj);
  EXPECT_NEAR(tangential.table(0, 1).kt, 8 * G, kTol * 8 * G);
  EXPECT_EQ(tangential.table(1, 0).kt, tangential.table(0, 1).kt);
  const double dt = 1e-3, u = 2e-6;  // one step imposes the tangential displacement u
  for (double delta : {1e-5, 1e-4, 1e-3, 1e-2}) {
    double xi[3] = {0, 0, 0}, f[3];
    const bool slid = tangential.force(pair(ai, aj, delta, 0, u / dt, 0, 1), 0.0, dt, xi, f);
    EXPECT_FALSE(slid);  // mu = infinity never slides
    EXPECT_NEAR(xi[1], u, 1e-15 * u);
    const double kt = 8 * G * std::sqrt(R * delta);
    EXPECT_NEAR(-f[1] / u, kt, kTol * kt) << delta;  // force / displacement
    EXPECT_EQ(f[0], 0.0);
    EXPECT_EQ(f[2], 0.0);
    // The restitution variant uses the same spring.
    CoulombTangential rest = tangential;
    rest.table.p[0][1].law = CoulombTangential::MindlinRestitution;
    double xr[3] = {0, 0, 0}, fr[3];
    rest.force(pair(ai, aj, delta, 0, u / dt, 0, 1), 0.0, dt, xr, fr);
    EXPECT_NEAR(-fr[1] / u, kt, kTol * kt) << delta;
  }
}

TEST(MindlinTangential, StiffnessFormStiffnessIsTwoGpOverTwoMinusNuSqrtDbarDelta) {
  const double Gp = 29e3, nu = 0.2, alpha_t = 20, ai = 1.0, aj = 0.6, dbar = ai + aj;
  const double inf = std::numeric_limits<double>::infinity();
  const auto tangential = CoulombTangential::uniform(2 * Gp / (2 - nu), alpha_t, inf, inf,
                                                     CoulombTangential::MindlinPairDiameter);
  const double dt = 1e-3, u = 2e-6, v = u / dt;
  for (double delta : {1e-5, 1e-4, 1e-3, 1e-2}) {
    double xi[3] = {0, 0, 0}, f[3];
    tangential.force(pair(ai, aj, delta, 0, v), 0.0, dt, xi, f);
    const double root = std::sqrt(dbar * delta);
    const double kt = 2 * Gp / (2 - nu) * root, gt = alpha_t * root;
    EXPECT_NEAR(-f[1], kt * u + gt * v, kTol * (kt * u + gt * v)) << delta;
    // Without the dashpot (elastic part): force / displacement = k_t.
    double fe[3];
    tangential.elastic_force(pair(ai, aj, delta), 0.0, xi, fe);
    EXPECT_NEAR(-fe[1] / u, kt, kTol * kt) << delta;
  }
}

TEST(MindlinTangential, SlidingCapsForceAtMuTimesHertzNormalForceAndShortensSpring) {
  // Hertz-Mindlin in the modulus form: push tangentially at constant speed; the force
  // grows as k_t u until mu f_n, where f_n is the Hertz force, then stays exactly there
  // and the spring holds mu f_n / k_t.
  const double E = 7e4, nu = 0.2, G = E / (2 * (1 + nu)), mu = 0.3, ai = 1.0, aj = 0.6;
  const double delta = 1e-3, R = ai * aj / (ai + aj);
  using Model = ContactModel<HertzNormal, CoulombTangential>;
  const Model model{
      {PairTable<HertzNormal::Params>::uniform(HertzNormal::modulus_form(E, nu, E, nu, 0.0))},
      CoulombTangential::uniform(8 * gstar(G, nu, G, nu), 0, mu, mu,
                                 CoulombTangential::MindlinReducedRadius),
      {}};
  const double fn = 4.0 / 3.0 * estar(E, nu, E, nu) * std::sqrt(R) * std::pow(delta, 1.5);
  const double kt = 8 * gstar(G, nu, G, nu) * std::sqrt(R * delta);
  const double dt = 1e-3, v = 1e-3;
  const int to_slide = static_cast<int>(std::ceil(mu * fn / (kt * v * dt)));
  ASSERT_GT(to_slide, 10);
  ASSERT_LT(to_slide, 400);
  double h[Model::history] = {};
  const PairState s = pair(ai, aj, delta, 0, v);
  double u = 0;
  for (int step = 0; step < 500; ++step) {
    PairForce out;
    model.evaluate(s, dt, h, out);
    u += v * dt;
    EXPECT_NEAR(out.fn, fn, kTol * fn);
    const double expected = std::min(kt * u, mu * fn);
    if (kt * u >= mu * fn) u = mu * fn / kt;  // sliding shortens the spring
    // The spring is a running sum over up to 400 steps: 1e-12 relative.
    EXPECT_NEAR(-out.ft[1], expected, 1e-12 * mu * fn) << step;
    // Torque on i from the tangential force at lever a_i - delta/2: -l_i n x f_t.
    EXPECT_NEAR(out.q[2], -(ai - 0.5 * delta) * out.ft[1], 1e-15 * mu * fn) << step;
  }
  EXPECT_NEAR(std::fabs(h[1]), mu * fn / kt, 1e-12 * mu * fn / kt);
}

TEST(MindlinTangential, InfiniteFrictionNeverSlidesEvenAtZeroNormalForce) {
  // mu = infinity ("no sliding", elastic probing) must hold the spring for any normal force,
  // including f_n = 0 exactly, where the Coulomb limit inf * 0 is not a number.
  const double inf = std::numeric_limits<double>::infinity();
  const auto tangential = CoulombTangential::uniform(8e4, 0, inf, inf);
  for (double fn : {0.0, -0.0, 1.0}) {
    double xi[3] = {0, 0, 0}, f[3];
    const bool slid = tangential.force(pair(1.0, 1.0, 1e-3, 0, 1.0), fn, 1e-3, xi, f);
    EXPECT_FALSE(slid) << fn;
    EXPECT_EQ(xi[1], 1e-3) << fn;
    EXPECT_EQ(f[1], -8e4 * 1e-3) << fn;
  }
}
