// Multi-contact force laws (MC-strain, MC-stress; docs/model_multicontact.md): a particle with a
// single contact is exactly classical Hertz under both, the MC-stress option that counts the
// pair's own contact against its closed form, MC-strain's correction against the formula
// evaluated by hand for contacts at 90 and 180 degrees (pair and wall contacts), momentum
// conservation, invariance under a rigid rotation, and the previous forces of MC-strain
// carried across neighbour-list rebuilds and particle reordering.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/dem/walls.hpp"
#include "core/run/kernel_times.hpp"
#include "kernels/cpu/contact_batch.hpp"
#include "kernels/dem/dem_system.hpp"
#include "kernels/dem/multicontact.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
// Rubber of the reference scenes (docs/model_multicontact.md §5); a softer second species for
// mixtures.
constexpr double kE = 1.85e6, kNu = 0.46, kRho = 2000, kA = 0.01;
constexpr double kE1 = 1.0e6, kNu1 = 0.3;
constexpr int kWallSlot = 2;  // species slot of the walls' (rigid) material

using Hertz = ContactModel<HertzNormal>;
using HertzFriction = ContactModel<HertzNormal, CoulombTangential, RollingTorsion>;

// Hertz modulus form for species 0 and 1 and a rigid wall slot; `visc` is the dashpot.
HertzNormal hertz(double visc) {
  const double E[2] = {kE, kE1}, nu[2] = {kNu, kNu1};
  HertzNormal h{
      PairTable<HertzNormal::Params>::uniform(HertzNormal::modulus_form(kE, kNu, kE, kNu, visc))};
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b)
      h.table.p[a][b] = HertzNormal::modulus_form(E[a], nu[a], E[b], nu[b], visc);
    h.table.p[a][kWallSlot] = h.table.p[kWallSlot][a] =
        HertzNormal::modulus_form(E[a], nu[a], kInf, 0.0, visc);
  }
  return h;
}
Hertz frictionless(double visc = 0.0) { return {hertz(visc), {}, {}}; }
HertzFriction frictional(double visc) {
  const double g = kE / (2 * (1 + kNu)), gstar = g / (2 * (2 - kNu));
  RollingTorsion::Params r;
  r.kr = 200, r.mur = 0.05, r.ko = 200, r.muo = 0.05;
  return {
      hertz(visc),
      CoulombTangential::uniform(8 * gstar, 0.0, 0.5, 0.5, CoulombTangential::MindlinReducedRadius),
      RollingTorsion::uniform(r)};
}

MultiContact law(MultiContact::Mode mode) {
  MultiContact mc;
  mc.mode = mode;
  mc.gamma = 1.12, mc.beta = 1.65;
  mc.young[0] = kE, mc.poisson[0] = kNu;
  mc.young[1] = kE1, mc.poisson[1] = kNu1;
  mc.young[kWallSlot] = kInf, mc.poisson[kWallSlot] = 0.0;
  return mc;
}

PeriodicBox open_box(double lo, double len) {
  PeriodicBox b;
  for (int d = 0; d < 3; ++d) b.lo[d] = lo, b.len[d] = len, b.periodic[d] = false;
  return b;
}
DemParams params(double dt = 2e-5, double skin = 0.1 * kA) {
  DemParams p;
  p.dt = dt, p.skin = skin;
  return p;
}
WallSpec floor_wall() {
  WallSpec w;
  w.name = "floor";
  w.normal[2] = -1;  // particles above z = 0
  w.material = kWallSlot;
  return w;
}
HostParticles particles(const std::vector<std::array<double, 5>>& rows) {
  HostParticles h;
  h.resize(static_cast<int>(rows.size()));
  for (size_t i = 0; i < rows.size(); ++i) {
    h.x[i] = rows[i][0], h.y[i] = rows[i][1], h.z[i] = rows[i][2], h.radius[i] = rows[i][3];
    h.density[i] = kRho, h.species[i] = static_cast<int>(rows[i][4]);
  }
  return h;
}

// An (n x 3) per-particle view by particle identity, flattened.
template <class Sys, class View>
std::vector<double> by_id(const Sys& sys, const View& v) {
  auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().id);
  std::vector<double> out(3 * host.extent(0));
  for (size_t i = 0; i < host.extent(0); ++i)
    for (int d = 0; d < 3; ++d) out[3 * id(i) + d] = host(i, d);
  return out;
}
template <class Sys>
std::vector<double> forces(const Sys& sys) {
  return by_id(sys, sys.particles().f);
}

// A jittered cubic lattice of overlapping spheres (two species, radii +-5 %), random velocities.
HostParticles cluster(int per_side, double spacing, double speed, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  HostParticles h;
  h.resize(per_side * per_side * per_side);
  int k = 0;
  for (int i = 0; i < per_side; ++i)
    for (int j = 0; j < per_side; ++j)
      for (int l = 0; l < per_side; ++l, ++k) {
        h.x[k] = i * spacing + 0.03 * kA * u(rng);
        h.y[k] = j * spacing + 0.03 * kA * u(rng);
        h.z[k] = l * spacing + 0.03 * kA * u(rng);
        h.vx[k] = speed * u(rng), h.vy[k] = speed * u(rng), h.vz[k] = speed * u(rng);
        h.radius[k] = kA * (1.0 + 0.05 * u(rng));
        h.density[k] = kRho;
        h.species[k] = k % 2;
      }
  return h;
}

// Every step's forces, torques, positions, velocities, spins (by identity) and wall loads.
template <class Exec, class Model>
std::vector<double> trajectory(const Model& model, const HostParticles& h, const PeriodicBox& box,
                               const std::vector<WallSpec>& walls, const MultiContact* mc,
                               long steps, double gravity = 0.0, bool batched = true) {
  DemParams prm = params();
  prm.gravity[2] = gravity;
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
  sys.set_batched_contacts(batched);
  if (!walls.empty()) sys.set_walls(walls);
  if (mc) sys.set_multicontact(*mc);
  std::vector<double> out;
  auto append = [&](const std::vector<double>& v) { out.insert(out.end(), v.begin(), v.end()); };
  for (long s = 0; s <= steps; ++s) {
    if (s > 0) sys.step(1);
    append(forces(sys));
    append(by_id(sys, sys.particles().torque));
    append(by_id(sys, sys.particles().x));
    append(by_id(sys, sys.particles().v));
    append(by_id(sys, sys.particles().w));
    for (const WallLoad& l : sys.wall_loads()) append({l.force[0], l.force[1], l.force[2]});
  }
  return out;
}

// Hertz force (4/3) E* sqrt(R* delta) delta of the tests' materials, written out.
double hertz_force(double estar, double rstar, double delta) {
  return 4.0 / 3.0 * estar * std::sqrt(rstar * delta) * delta;
}
double estar_pair(double E1, double nu1, double E2, double nu2) {
  return 1.0 / ((1 - nu1 * nu1) / E1 + (1 - nu2 * nu2) / E2);
}

// MC-strain's formula with plain doubles, from the contact points and inward normals:
// the displacement at contact point xc (inward normal nc) caused by force fk at point xk.
double hand_overlap(const double nk[3], const double xk[3], const double nc[3], const double xc[3],
                    double fk, double E, double nu, double gamma) {
  double u[3], d = 0;
  for (int q = 0; q < 3; ++q) u[q] = xc[q] - xk[q], d += u[q] * u[q];
  d = std::sqrt(d);
  for (double& c : u) c /= d;
  double nku = 0, ncu = 0, nkc = 0, sum_c = 0;
  for (int q = 0; q < 3; ++q) {
    nku += nk[q] * u[q], ncu += nc[q] * u[q], nkc += nk[q] * nc[q];
    sum_c += (nk[q] + u[q]) * nc[q];
  }
  const double bracket = nku * ncu + (3 - 4 * nu) * nkc - (1 - 2 * nu) * sum_c / (1 + nku);
  return -gamma * (1 + nu) * fk / (2 * M_PI * E * d) * bracket;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::fabs(x));
  return m;
}
}  // namespace

template <class T>
class MultiContactTest : public ::testing::Test {};
TYPED_TEST_SUITE(MultiContactTest, granular::testing::ExecSpaces);

TYPED_TEST(MultiContactTest, SingleContactIsExactlyClassicalHertzUnderBothCorrections) {
  using Exec = TypeParam;
  // Damped, frictional, rolling: every part of the model runs through the corrected paths.
  const auto model = frictional(5.0);
  // Two spheres in an oblique, spinning collision (no other contacts: both corrections
  // vanish), and one sphere hitting the floor obliquely (its only contact is the wall).
  HostParticles pair = particles({{0, 0, 0, kA, 0}, {1.75 * kA, 0.6 * kA, 0.1 * kA, 0.8 * kA, 1}});
  pair.vx[0] = 1.0, pair.vz[1] = 0.2;
  HostParticles one = particles({{0, 0, 1.02 * kA, kA, 0}});
  one.vz[0] = -1.0, one.vx[0] = 0.3;
  const PeriodicBox box = open_box(-5 * kA, 10 * kA);
  const long steps = 400;  // through the whole contact and beyond
  for (const bool wall : {false, true}) {
    const HostParticles& h = wall ? one : pair;
    const std::vector<WallSpec> walls =
        wall ? std::vector<WallSpec>{floor_wall()} : std::vector<WallSpec>{};
    const auto classical = trajectory<Exec>(model, h, box, walls, nullptr, steps, -9.81);
    for (const auto mode : {MultiContact::None, MultiContact::Strain, MultiContact::Stress}) {
      const MultiContact mc = law(mode);
      const auto corrected = trajectory<Exec>(model, h, box, walls, &mc, steps, -9.81);
      ASSERT_EQ(corrected.size(), classical.size());
      size_t differ = 0, first = 0;
      for (size_t k = 0; k < classical.size(); ++k)
        if (corrected[k] != classical[k] && differ++ == 0) first = k;
      EXPECT_EQ(differ, 0u) << (wall ? "wall" : "pair") << ", mode " << mode << ": first at "
                            << first << ": " << corrected[first] << " vs " << classical[first];
    }
  }
}

TYPED_TEST(MultiContactTest, StressOwnContactOptionAddsThePairsOwnPressure) {
  using Exec = TypeParam;
  // Two equal spheres at rest with overlap delta. Counting the pair's own contact in both
  // stresses: tr sigma = -(a - delta/2) f_H / V for each, P = -(2 tr sigma)/3, and the force
  // is f_H + beta nu pi R* delta P; `mean` halves P.
  const double a = kA, delta = 0.08 * a;
  const HostParticles h = particles({{0, 0, 0, a, 0}, {2 * a - delta, 0, 0, a, 0}});
  const PeriodicBox box = open_box(-5 * a, 10 * a);
  DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), box, frictionless(), params());
  const double fh = hertz_force(estar_pair(kE, kNu, kE, kNu), 0.5 * a, delta);
  EXPECT_NEAR(-forces(sys)[0], fh, 1e-13 * fh);
  const double volume = 4.0 / 3.0 * M_PI * a * a * a;
  const double tr = -(a - 0.5 * delta) * fh / volume;
  const double area = M_PI * 0.5 * a * delta;
  for (const bool mean : {false, true}) {
    MultiContact mc = law(MultiContact::Stress);
    mc.own_contact = true, mc.mean = mean;
    sys.set_multicontact(mc);
    const double p = -(tr + tr) / (mean ? 6.0 : 3.0);
    const double expected = fh + mc.beta * kNu * area * p;
    const auto f = forces(sys);
    EXPECT_NEAR(-f[0], expected, 1e-13 * fh) << "mean " << mean;
    EXPECT_EQ(f[0], -f[3]);                // action and reaction, exactly
    EXPECT_GT(expected, fh * (1 + 1e-3));  // the option matters: compression stiffens
  }
}

TYPED_TEST(MultiContactTest, StrainCorrectionMatchesHandEvaluationForOppositeContacts) {
  using Exec = TypeParam;
  // Three equal spheres in a row along x: A - B - C, overlaps d1 (AB) and d2 (BC), at rest.
  // B's two contacts are diametrically opposite. The previous forces are the classical Hertz
  // forces of this state (set_multicontact seeds them); A and C have one contact each, so
  // the force on A is f_H(d1 + delta_(BC->AB)) and on C f_H(d2 + delta_(AB->BC)), with B's
  // E and nu. For 180 degrees the formula reduces to
  //   delta_(k->c) = gamma (1 + nu)(3 - 2 nu) f_k / (2 pi E d),  d = (a - d1/2) + (a - d2/2).
  const double a = kA, d1 = 0.05 * a, d2 = 0.09 * a;
  const HostParticles h =
      particles({{-(2 * a - d1), 0, 0, a, 0}, {0, 0, 0, a, 0}, {2 * a - d2, 0, 0, a, 0}});
  DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), open_box(-5 * a, 10 * a),
                             frictionless(), params());
  const MultiContact mc = law(MultiContact::Strain);
  sys.set_multicontact(mc);
  const double estar = estar_pair(kE, kNu, kE, kNu), rstar = 0.5 * a;
  const double f1 = hertz_force(estar, rstar, d1), f2 = hertz_force(estar, rstar, d2);
  const double d = (a - 0.5 * d1) + (a - 0.5 * d2);
  const double closed = mc.gamma * (1 + kNu) * (3 - 2 * kNu) / (2 * M_PI * kE * d);
  // The same from the general formula with B's contact points and inward normals.
  const double n_ab[3] = {1, 0, 0}, x_ab[3] = {-(a - 0.5 * d1), 0, 0};
  const double n_bc[3] = {-1, 0, 0}, x_bc[3] = {a - 0.5 * d2, 0, 0};
  const double to_ab = hand_overlap(n_bc, x_bc, n_ab, x_ab, f2, kE, kNu, mc.gamma);
  const double to_bc = hand_overlap(n_ab, x_ab, n_bc, x_bc, f1, kE, kNu, mc.gamma);
  EXPECT_NEAR(to_ab, closed * f2, 1e-14 * closed * f2);
  EXPECT_NEAR(to_bc, closed * f1, 1e-14 * closed * f1);
  EXPECT_GT(to_ab, 0.05 * d1);  // the correction is large enough to be seen
  const auto f = forces(sys);
  const double fa = hertz_force(estar, rstar, d1 + to_ab),
               fc = hertz_force(estar, rstar, d2 + to_bc);
  EXPECT_NEAR(-f[0], fa, 1e-12 * fa);
  EXPECT_NEAR(f[6], fc, 1e-12 * fc);
  EXPECT_NEAR(f[3], fa - fc, 1e-12 * fc);  // B gets both, exactly the reactions
  for (int q : {1, 2, 4, 5, 7, 8}) EXPECT_EQ(f[q], 0.0);
}

TEST(MultiContactStrainPair, BothDirectionsMatchTheVectorFormulaAndSwappingGivesTheSameBits) {
  // strain_pair's scalar form against strain_overlap's vector form, for random normals and
  // levers (opposite, near-parallel and everything between), and the symmetry the sums use.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), lever(0.5, 1.0);
  auto unit = [&](double n[3]) {
    double r = 0;
    for (int d = 0; d < 3; ++d) n[d] = u(rng), r += n[d] * n[d];
    r = std::sqrt(r);
    for (int d = 0; d < 3; ++d) n[d] /= r;
  };
  const double pref = -0.7, nu = 0.46, fk = 3.0, fc = 5.0;
  for (int t = 0; t < 2000; ++t) {
    double nk[3], nc[3];
    unit(nk), unit(nc);
    if (t % 4 == 1)
      for (int d = 0; d < 3; ++d) nc[d] = -nk[d];  // diametrically opposite
    const double lk = lever(rng), lc = lever(rng);
    double g_kc, g_ck, h_kc, h_ck;
    strain_pair(nk, lk, nc, lc, nu, g_kc, g_ck);
    strain_pair(nc, lc, nk, lk, nu, h_kc, h_ck);
    EXPECT_EQ(g_kc, h_ck);
    EXPECT_EQ(g_ck, h_kc);
    const double v_kc = strain_overlap(nk, lk, fk, nc, lc, pref, nu);
    const double v_ck = strain_overlap(nc, lc, fc, nk, lk, pref, nu);
    EXPECT_NEAR(pref * fk * g_kc, v_kc, 1e-12 * std::fabs(v_kc) + 1e-300) << t;
    EXPECT_NEAR(pref * fc * g_ck, v_ck, 1e-12 * std::fabs(v_ck) + 1e-300) << t;
  }
}

#if GRANULAR_HOST_AVX
TEST(MultiContactStrainPair, FourPartnersAtATimeGiveTheBitsOfOneAtATime) {
  // strain_sums_avx against strain_sums over the same contacts (random normals, levers and
  // forces, some forces zero), every count from 1 to the stack's: the same sums, bit for bit.
  if (!cpu_has_avx()) GTEST_SKIP() << "no AVX on this processor";
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0), lever(0.5, 1.0);
  constexpr int K = multicontact::kStrainStackContacts, P = K + 3;
  const double pref = -0.31, nu = 0.42;
  for (int nt = 1; nt <= K; ++nt) {
    double n0[P], n1[P], n2[P], l[P], f[P], lanes[P] = {}, one[P] = {};
    for (int t = 0; t < nt; ++t) {
      double n[3], r = 0;
      for (double& c : n) c = u(rng), r += c * c;
      r = std::sqrt(r);
      n0[t] = n[0] / r, n1[t] = n[1] / r, n2[t] = n[2] / r;
      l[t] = lever(rng), f[t] = t % 5 == 2 ? 0.0 : 10 * lever(rng);
    }
    for (int t = nt; t < P; ++t)
      n0[t] = n0[nt - 1], n1[t] = n1[nt - 1], n2[t] = n2[nt - 1], l[t] = l[nt - 1],
      f[t] = f[nt - 1];
    strain_sums_avx(nt, pref, nu, n0, n1, n2, l, f, lanes);
    strain_sums(
        nt, pref, nu,
        [&](int t, double n[3], double& lv, double& fv) {
          n[0] = n0[t], n[1] = n1[t], n[2] = n2[t];
          lv = l[t], fv = f[t];
        },
        [&](int t, double v) { one[t] += v; });
    for (int t = 0; t < nt; ++t) EXPECT_EQ(lanes[t], one[t]) << nt << " contacts, contact " << t;
    if (nt > 2) {
      EXPECT_NE(one[0], 0.0);
    }
  }
}
#endif

TYPED_TEST(MultiContactTest, StrainCorrectionOfManyContactsMatchesHandEvaluationFromStackAndRows) {
  using Exec = TypeParam;
  // A big sphere touched by m small ones spread over its surface (which do not touch each
  // other), at rest. Each small sphere's only contact is with the big one, so its force is
  // f_H(delta_j + S(c_j)), S(c_j) the sum over the big sphere's other contacts of the overlap
  // their previous (classical) forces cause at c_j. m = 20 sums from the stack, m = 40 from
  // the rows (more touching contacts than the stack holds): both against the hand formula.
  const double a = kA, as = 0.25 * kA;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> overlap(0.02, 0.08);
  for (const int m : {20, 40}) {
    std::vector<std::array<double, 5>> rows{{0, 0, 0, a, 0}};
    std::vector<std::array<double, 3>> normal;  // big sphere's inward normals
    std::vector<double> delta;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int j = 0; j < m; ++j) {
      const double z = 1.0 - (j + 0.5) * 2.0 / m, r = std::sqrt(1.0 - z * z);
      const double e[3] = {r * std::cos(golden * j), r * std::sin(golden * j), z};
      const double dj = overlap(rng) * as, dist = a + as - dj;
      rows.push_back({dist * e[0], dist * e[1], dist * e[2], as, 0});
      normal.push_back({-e[0], -e[1], -e[2]});
      delta.push_back(dj);
    }
    DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(particles(rows)),
                               open_box(-5 * a, 10 * a), frictionless(), params());
    const MultiContact mc = law(MultiContact::Strain);
    sys.set_multicontact(mc);
    const double estar = estar_pair(kE, kNu, kE, kNu), rstar = a * as / (a + as);
    std::vector<double> classical(m);
    for (int j = 0; j < m; ++j) classical[j] = hertz_force(estar, rstar, delta[j]);
    const auto f = forces(sys);
    for (int c = 0; c < m; ++c) {
      const double xc[3] = {-(a - 0.5 * delta[c]) * normal[c][0],
                            -(a - 0.5 * delta[c]) * normal[c][1],
                            -(a - 0.5 * delta[c]) * normal[c][2]};
      double s = 0;
      for (int k = 0; k < m; ++k) {
        if (k == c) continue;
        const double xk[3] = {-(a - 0.5 * delta[k]) * normal[k][0],
                              -(a - 0.5 * delta[k]) * normal[k][1],
                              -(a - 0.5 * delta[k]) * normal[k][2]};
        s += hand_overlap(normal[k].data(), xk, normal[c].data(), xc, classical[k], kE, kNu,
                          mc.gamma);
      }
      const double fj = hertz_force(estar, rstar, delta[c] + s);
      double fr = 0;  // the force on the small sphere, along the big sphere's outward normal
      for (int d = 0; d < 3; ++d) fr -= f[3 * (c + 1) + d] * normal[c][d];
      EXPECT_NEAR(fr, fj, 1e-11 * fj) << "m " << m << " contact " << c;
      EXPECT_GT(std::fabs(fj - classical[c]), 1e-3 * classical[c]);  // the correction shows
    }
  }
}

TYPED_TEST(MultiContactTest, PairPassesInBatchesGiveTheContactByContactBits) {
  using Exec = TypeParam;
  // The pair passes of both laws evaluated four contacts at a time (host, AVX) against the
  // contact-by-contact passes (MC-stress: the classical law; MC-strain: the law with the
  // corrected overlap): every step's forces, torques, positions, velocities, spins and wall
  // loads, bit for bit, for a frictional two-species cluster on a floor under gravity. The
  // kernel timer shows that the batch ran.
  using Model = ContactModel<HertzNormal, CoulombTangential>;
  const double g = kE / (2 * (1 + kNu)), gstar = g / (2 * (2 - kNu));
  Model model;
  model.normal = hertz(2.0);
  model.tangential =
      CoulombTangential::uniform(8 * gstar, 0.0, 0.5, 0.5, CoulombTangential::MindlinReducedRadius);
  if (!forces_by_slabs<Exec>() || !cpu_has_avx() || !ContactBatchLaw<Model>::usable(model))
    GTEST_SKIP() << "no batched contacts on this backend or processor";
  HostParticles h = cluster(4, 1.9 * kA, 0.2, 3);
  for (int i = 0; i < h.size(); ++i) h.z[i] += 0.97 * kA;  // the lowest layer presses on the floor
  for (const auto mode : {MultiContact::Stress, MultiContact::Strain}) {
    const std::string batched_kernel = mode == MultiContact::Stress
                                           ? "dem::multicontact::stress_pairs_batched"
                                           : "dem::multicontact::strain_pairs_batched";
    auto run = [&](bool batched, long& batched_calls) {
      const MultiContact mc = law(mode);
      kernel_times::start(false);
      const auto out = trajectory<Exec>(model, h, open_box(-10 * kA, 25 * kA), {floor_wall()}, &mc,
                                        200, -9.81, batched);
      kernel_times::stop();
      batched_calls = 0;
      for (const auto& r : kernel_times::regions())
        for (const auto& k : r.kernels)
          if (k.name == batched_kernel) batched_calls += k.calls;
      return out;
    };
    long calls_on = 0, calls_off = 0;
    const auto on = run(true, calls_on), off = run(false, calls_off);
    EXPECT_GE(calls_on, 200) << mode;
    EXPECT_EQ(calls_off, 0) << mode;
    ASSERT_EQ(on.size(), off.size());
    size_t differ = 0;
    for (size_t q = 0; q < on.size(); ++q) differ += on[q] != off[q];
    EXPECT_EQ(differ, 0u) << mode;
    EXPECT_GT(max_abs(on), 0.0);
  }
}

TYPED_TEST(MultiContactTest, StrainCorrectionMatchesHandEvaluationForWallAndSphereAtRightAngle) {
  using Exec = TypeParam;
  // Sphere B rests on the floor (overlap dw) and touches a smaller sphere A beside it along
  // x (overlap d1, A clear of the floor): B's contacts are at 90 degrees, one of them a wall.
  // A has only the pair contact, so the force on A is f_H(d1 + delta_(wall->AB)) with B's
  // material, and the wall's force on B is f_H,wall(dw + delta_(AB->wall)) (rigid wall: no
  // second term). The previous forces are the classical forces of this state.
  const double a = kA, aa = 0.5 * kA, dw = 0.06 * a, d1 = 0.07 * aa;
  const double zb = a - dw;
  const HostParticles h = particles({{-(a + aa - d1), 0, zb, aa, 0}, {0, 0, zb, a, 0}});
  for (const bool walls : {true, false}) {
    DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), open_box(-5 * a, 10 * a),
                               frictionless(), params());
    sys.set_walls({floor_wall()});
    MultiContact mc = law(MultiContact::Strain);
    mc.walls = walls;
    sys.set_multicontact(mc);
    const double es_pair = estar_pair(kE, kNu, kE, kNu), rs_pair = a * aa / (a + aa);
    const double es_wall = kE / (1 - kNu * kNu);
    const double f1 = hertz_force(es_pair, rs_pair, d1), fw = hertz_force(es_wall, a, dw);
    // B's contact points (relative to its centre) and inward normals.
    const double n_ab[3] = {1, 0, 0}, x_ab[3] = {-(a - 0.5 * d1), 0, 0};
    const double n_w[3] = {0, 0, 1}, x_w[3] = {0, 0, -(a - 0.5 * dw)};
    const double to_ab = walls ? hand_overlap(n_w, x_w, n_ab, x_ab, fw, kE, kNu, mc.gamma) : 0.0;
    const double to_w = walls ? hand_overlap(n_ab, x_ab, n_w, x_w, f1, kE, kNu, mc.gamma) : 0.0;
    if (walls) {
      EXPECT_GT(to_ab, 0.01 * d1);  // bulging: the side contact gets stiffer
    }
    const auto f = forces(sys);
    const double fa = hertz_force(es_pair, rs_pair, d1 + to_ab);
    const double fb = hertz_force(es_wall, a, dw + to_w);
    EXPECT_NEAR(-f[0], fa, 1e-12 * fa) << "walls " << walls;
    EXPECT_NEAR(f[3], fa, 1e-12 * fa) << "walls " << walls;
    EXPECT_NEAR(f[5], fb, 1e-12 * fb) << "walls " << walls;
    EXPECT_NEAR(-sys.wall_loads()[0].force[2], fb, 1e-12 * fb) << "walls " << walls;
    EXPECT_EQ(f[2], 0.0);  // A is clear of the floor
  }
}

TYPED_TEST(MultiContactTest, StressCorrectionMatchesHandEvaluationForWallAndSphere) {
  using Exec = TypeParam;
  // The geometry of the previous test under MC-stress (own contacts left out of the traces).
  // Pair AB: A has no other contact, B's other contact is the wall, so
  //   P_AB = -(tr_B without AB)/3 = (a - dw/2) f_w / (3 V_B);
  // wall contact of B: P_w = -(tr_B without the wall)/3 = (a - d1/2) f_1 / (3 V_B), with the
  // classical forces f_1, f_w of the first pass; each contact gets beta nu pi R* delta P.
  const double a = kA, aa = 0.5 * kA, dw = 0.06 * a, d1 = 0.07 * aa;
  const double zb = a - dw;
  const HostParticles h = particles({{-(a + aa - d1), 0, zb, aa, 0}, {0, 0, zb, a, 0}});
  for (const bool walls : {true, false}) {
    DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), open_box(-5 * a, 10 * a),
                               frictionless(), params());
    sys.set_walls({floor_wall()});
    MultiContact mc = law(MultiContact::Stress);
    mc.walls = walls;
    sys.set_multicontact(mc);
    const double rs_pair = a * aa / (a + aa);
    const double f1 = hertz_force(estar_pair(kE, kNu, kE, kNu), rs_pair, d1);
    const double fw = hertz_force(kE / (1 - kNu * kNu), a, dw);
    const double vb = 4.0 / 3.0 * M_PI * a * a * a;
    const double p_ab = walls ? (a - 0.5 * dw) * fw / (3 * vb) : 0.0;
    const double p_w = walls ? (a - 0.5 * d1) * f1 / (3 * vb) : 0.0;
    const double fa = f1 + mc.beta * kNu * M_PI * rs_pair * d1 * p_ab;
    const double fb = fw + mc.beta * kNu * M_PI * a * dw * p_w;
    if (walls) {
      EXPECT_GT(fa, f1 * (1 + 1e-3));  // large enough to be seen
      EXPECT_GT(fb, fw * (1 + 1e-4));
    }
    const auto f = forces(sys);
    EXPECT_NEAR(-f[0], fa, 1e-12 * fa) << "walls " << walls;
    EXPECT_EQ(f[3], -f[0]) << "walls " << walls;  // action and reaction, exactly
    EXPECT_NEAR(f[5], fb, 1e-12 * fb) << "walls " << walls;
    EXPECT_NEAR(-sys.wall_loads()[0].force[2], fb, 1e-12 * fb) << "walls " << walls;
  }
}

// The same geometry with the particle-scale area of MC-stress (stress_area = "particle"): each
// correction is beta nu pi R*^2 P instead of beta nu pi R* delta P, R*/delta = 9.5 times
// larger here.
TYPED_TEST(MultiContactTest, StressParticleAreaCorrectionMatchesHandEvaluationForWallAndSphere) {
  using Exec = TypeParam;
  const double a = kA, aa = 0.5 * kA, dw = 0.06 * a, d1 = 0.07 * aa;
  const double zb = a - dw;
  const HostParticles h = particles({{-(a + aa - d1), 0, zb, aa, 0}, {0, 0, zb, a, 0}});
  DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), open_box(-5 * a, 10 * a),
                             frictionless(), params());
  sys.set_walls({floor_wall()});
  MultiContact mc = law(MultiContact::Stress);
  mc.area = MultiContact::ParticleArea;
  sys.set_multicontact(mc);
  const double rs_pair = a * aa / (a + aa);
  const double f1 = hertz_force(estar_pair(kE, kNu, kE, kNu), rs_pair, d1);
  const double fw = hertz_force(kE / (1 - kNu * kNu), a, dw);
  const double vb = 4.0 / 3.0 * M_PI * a * a * a;
  const double p_ab = (a - 0.5 * dw) * fw / (3 * vb);
  const double p_w = (a - 0.5 * d1) * f1 / (3 * vb);
  const double fa = f1 + mc.beta * kNu * M_PI * rs_pair * rs_pair * p_ab;
  const double fb = fw + mc.beta * kNu * M_PI * a * a * p_w;
  const double fa_hertz = f1 + mc.beta * kNu * M_PI * rs_pair * d1 * p_ab;
  EXPECT_GT(fa - f1, 9 * (fa_hertz - f1));  // the two readings differ by R*/delta = 9.5
  const auto f = forces(sys);
  EXPECT_NEAR(-f[0], fa, 1e-12 * fa);
  EXPECT_EQ(f[3], -f[0]);  // action and reaction, exactly
  EXPECT_NEAR(f[5], fb, 1e-12 * fb);
  // The time-step guard's allowance no longer scales with the largest overlap.
  EXPECT_EQ(stiffness_factor(mc, 0.1), stiffness_factor(mc, 0.5));
  mc.area = MultiContact::HertzArea;
  EXPECT_LT(stiffness_factor(mc, 0.1), stiffness_factor(mc, 0.5));
}

TYPED_TEST(MultiContactTest, BothCorrectionsConserveMomentumToRoundOff) {
  using Exec = TypeParam;
  const HostParticles h = cluster(3, 1.86 * kA, 0.3, 7);
  for (const auto mode : {MultiContact::Strain, MultiContact::Stress}) {
    DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), open_box(-10 * kA, 25 * kA),
                               frictionless(2.0), params());
    sys.set_multicontact(law(mode));
    auto momentum = [&](double& scale) {
      auto v = by_id(sys, sys.particles().v);
      auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().mass);
      auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().id);
      std::array<double, 3> p{0, 0, 0};
      scale = 0;
      for (int i = 0; i < sys.particles().n; ++i)
        for (int d = 0; d < 3; ++d) {
          p[d] += m(i) * v[3 * id(i) + d];
          scale += m(i) * std::fabs(v[3 * id(i) + d]);
        }
      return p;
    };
    const auto f0 = forces(sys);
    double fsum[3] = {0, 0, 0};
    for (size_t k = 0; k < f0.size(); ++k) fsum[k % 3] += f0[k];
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(fsum[d], 0.0, 1e-13 * max_abs(f0)) << mode;
    double s0, s1;
    const auto p0 = momentum(s0);
    sys.step(300);
    const auto p1 = momentum(s1);
    EXPECT_GT(s1, 2 * s0);  // the overlaps drove the cluster apart: forces were large
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(p1[d], p0[d], 1e-13 * s1) << mode;
  }
}

TYPED_TEST(MultiContactTest, BothCorrectionsAreInvariantUnderRigidRotation) {
  using Exec = TypeParam;
  const HostParticles h = cluster(3, 1.85 * kA, 0.2, 11);
  // Rotation by 0.7 rad about (1, 2, 3)/sqrt(14), about the cluster's middle.
  const double axis[3] = {1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)};
  const double c = std::cos(0.7), s = std::sin(0.7);
  double R[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double eps = (i + 1) % 3 == j ? 1.0 : (j + 1) % 3 == i ? -1.0 : 0.0;
      const int k = 3 - i - j;
      R[i][j] =
          (i == j ? c : 0.0) + (1 - c) * axis[i] * axis[j] - (i != j ? eps * s * axis[k] : 0.0);
    }
  const double mid = 1.85 * kA;
  HostParticles hr = h;
  for (int p = 0; p < h.size(); ++p) {
    const double x[3] = {h.x[p] - mid, h.y[p] - mid, h.z[p] - mid};
    const double v[3] = {h.vx[p], h.vy[p], h.vz[p]};
    double xr[3] = {0, 0, 0}, vr[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) xr[i] += R[i][j] * x[j], vr[i] += R[i][j] * v[j];
    hr.x[p] = xr[0] + mid, hr.y[p] = xr[1] + mid, hr.z[p] = xr[2] + mid;
    hr.vx[p] = vr[0], hr.vy[p] = vr[1], hr.vz[p] = vr[2];
  }
  const PeriodicBox box = open_box(-15 * kA, 35 * kA);
  for (const auto mode : {MultiContact::Strain, MultiContact::Stress}) {
    DemSystem<Exec, Hertz> a(Particles<Exec>::from_host(h), box, frictionless(2.0), params());
    DemSystem<Exec, Hertz> b(Particles<Exec>::from_host(hr), box, frictionless(2.0), params());
    DemSystem<Exec, Hertz> classical(Particles<Exec>::from_host(h), box, frictionless(2.0),
                                     params());
    a.set_multicontact(law(mode));
    b.set_multicontact(law(mode));
    for (int round = 0; round < 2; ++round) {
      const auto fa = forces(a), fb = forces(b), fc = forces(classical);
      const double scale = max_abs(fa);
      double worst = 0, change = 0;
      for (int p = 0; p < h.size(); ++p)
        for (int i = 0; i < 3; ++i) {
          double rotated = 0;
          for (int j = 0; j < 3; ++j) rotated += R[i][j] * fa[3 * p + j];
          worst = std::max(worst, std::fabs(fb[3 * p + i] - rotated));
          change = std::max(change, std::fabs(fa[3 * p + i] - fc[3 * p + i]));
        }
      EXPECT_LT(worst, 1e-12 * scale) << "mode " << mode << ", round " << round;
      EXPECT_GT(change, 1e-3 * scale) << "the correction must matter for the test to mean much";
      a.step(20), b.step(20), classical.step(20);
    }
  }
}

TYPED_TEST(MultiContactTest, StrainPreviousForcesSurviveRebuildsAndReordering) {
  using Exec = TypeParam;
  // A cluster dropped on the floor: pair and wall contacts open and close while particles
  // are reordered. Rebuilding (and re-sorting) every step must give the run the skin
  // criterion gives, up to the summation order of partners; dropping the previous forces
  // at a rebuild would change the forces by the whole correction.
  const HostParticles h = [] {
    HostParticles c = cluster(3, 1.9 * kA, 0.1, 5);
    for (double& z : c.z) z += 1.1 * kA;
    return c;
  }();
  auto run = [&](long rebuild_every, bool corrected, long& builds) {
    DemParams prm = params(2e-5, 0.3 * kA);
    prm.rebuild_every = rebuild_every, prm.gravity[2] = -9.81;
    DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), open_box(-10 * kA, 25 * kA),
                               frictionless(2.0), prm);
    sys.set_walls({floor_wall()});
    if (corrected) sys.set_multicontact(law(MultiContact::Strain));
    sys.step(1500);
    builds = sys.neighbor_list().builds();
    EXPECT_GT(sys.wall_loads()[0].contacts, 0.0);  // the floor carries the cluster
    return by_id(sys, sys.particles().x);
  };
  long every_builds = 0, skin_builds = 0, classical_builds = 0;
  const auto every = run(1, true, every_builds);
  const auto skin = run(0, true, skin_builds);
  const auto classical = run(0, false, classical_builds);
  EXPECT_GT(every_builds, 1499);
  EXPECT_GT(skin_builds, 2);
  EXPECT_LT(skin_builds, every_builds / 10);
  double worst = 0, effect = 0;
  for (size_t k = 0; k < every.size(); ++k) {
    worst = std::max(worst, std::fabs(every[k] - skin[k]));
    effect = std::max(effect, std::fabs(classical[k] - skin[k]));
  }
  // Only the summation order of partners differs between the runs.
  EXPECT_LT(worst, 1e-9 * kA);
  EXPECT_GT(effect, 1e-4 * kA);  // the correction moved the particles far more than that
}

TYPED_TEST(MultiContactTest, MaterialsOfSpeciesInUseAreValidated) {
  using Exec = TypeParam;
  const HostParticles h = particles({{0, 0, 0, kA, 0}, {1.95 * kA, 0, 0, kA, 1}});
  DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), open_box(-5 * kA, 10 * kA),
                             frictionless(), params());
  MultiContact mc = law(MultiContact::Strain);
  mc.young[1] = 0.0;  // species 1 is in use
  EXPECT_THROW(sys.set_multicontact(mc), InputError);
  mc = law(MultiContact::Stress);
  mc.young[1] = 0.0;  // MC-stress needs no modulus
  EXPECT_NO_THROW(sys.set_multicontact(mc));
  mc.poisson[0] = 0.7;
  EXPECT_THROW(sys.set_multicontact(mc), InputError);
  mc = law(MultiContact::Strain);
  mc.young[3] = -1.0;  // species 3 is not in use
  EXPECT_NO_THROW(sys.set_multicontact(mc));
}

namespace {
// Stiffness matrix of a cluster (3n x 3n, symmetrised) by central differences of the forces,
// each displaced state a fresh system: K = -dF/dx.
template <class Exec>
Eigen::MatrixXd stiffness_matrix(const HostParticles& h, const PeriodicBox& box,
                                 const MultiContact* mc, double max_overlap) {
  const int n = h.size(), m = 3 * n;
  const double step = 1e-6 * kA;
  DemParams prm = params(1e-9);  // far below every guard: only the forces are wanted
  prm.max_overlap = max_overlap;
  auto force_at = [&](int q, double shift) {
    HostParticles moved = h;
    double* coord[3] = {moved.x.data(), moved.y.data(), moved.z.data()};
    coord[q % 3][q / 3] += shift;
    DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(moved), box, frictionless(), prm);
    if (mc) sys.set_multicontact(*mc);
    return forces(sys);
  };
  Eigen::MatrixXd k(m, m);
  for (int q = 0; q < m; ++q) {
    const auto plus = force_at(q, step), minus = force_at(q, -step);
    for (int r = 0; r < m; ++r) k(r, q) = -(plus[r] - minus[r]) / (2 * step);
  }
  return 0.5 * (k + k.transpose());
}

// The centre and its twelve nearest neighbours of a face-centred cubic packing of equal
// spheres, every touching pair (centre-shell and shell-shell) at overlap `overlap` a.
HostParticles fcc_cluster(double overlap) {
  const double spacing = (2.0 - overlap) * kA / std::sqrt(2.0);  // half the cube's face diagonal
  std::vector<std::array<double, 5>> rows{{0, 0, 0, kA, 0}};
  for (int a = 0; a < 3; ++a)
    for (const int s1 : {-1, 1})
      for (const int s2 : {-1, 1}) {
        std::array<double, 5> r{0, 0, 0, kA, 0};
        r[(a + 1) % 3] = s1 * spacing, r[(a + 2) % 3] = s2 * spacing;
        rows.push_back(r);
      }
  return particles(rows);
}

// The largest time step the guard accepts for a system: bisection on the refusal.
template <class Exec>
double largest_accepted_dt(const HostParticles& h, const PeriodicBox& box, const MultiContact* mc) {
  double lo = 1e-12, hi = 1e-2;
  for (int it = 0; it < 60; ++it) {
    const double dt = std::sqrt(lo * hi);
    try {
      DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), box, frictionless(), params(dt));
      if (mc) sys.set_multicontact(*mc);
      lo = dt;
    } catch (const PhysicsError&) {
      hi = dt;
    }
  }
  return lo;
}
}  // namespace

TYPED_TEST(MultiContactTest, StressStiffeningOfADenseClusterStaysWithinTheTimeStepAllowance) {
  using Exec = TypeParam;
  // The stiffest mode of a 13-sphere fcc cluster at overlap mu a, by brute force, under MC-stress
  // against classical Hertz: the ratio must stay below the guard's allowance, and be above 1
  // (the allowance guards a real stiffening).
  const double mu = 0.3;
  const HostParticles h = fcc_cluster(mu);
  const PeriodicBox box = open_box(-5 * kA, 10 * kA);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> classical(
      stiffness_matrix<Exec>(h, box, nullptr, mu), Eigen::EigenvaluesOnly);
  for (const double beta : {1.65, 10.0}) {
    for (const bool own : {false, true}) {
      MultiContact mc = law(MultiContact::Stress);
      mc.beta = beta, mc.own_contact = own;
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> corrected(
          stiffness_matrix<Exec>(h, box, &mc, mu), Eigen::EigenvaluesOnly);
      const double ratio = corrected.eigenvalues().maxCoeff() / classical.eigenvalues().maxCoeff();
      const double allowance = stiffness_factor(mc, mu);
      ::testing::Test::RecordProperty(
          "beta_" + std::to_string(beta) + (own ? "_own" : "") + "_ratio_allowance",
          std::to_string(ratio) + " " + std::to_string(allowance));
      EXPECT_GT(ratio, 1.0 + 0.1 * (allowance - 1.0)) << "beta " << beta << " own " << own;
      EXPECT_LE(ratio, allowance) << "beta " << beta << " own " << own;
    }
  }
}

TYPED_TEST(MultiContactTest, TimeStepGuardAllowsForStressStiffeningOnly) {
  using Exec = TypeParam;
  const HostParticles h = fcc_cluster(0.1);
  const PeriodicBox box = open_box(-5 * kA, 10 * kA);
  const double classical = largest_accepted_dt<Exec>(h, box, nullptr);
  MultiContact stress = law(MultiContact::Stress);
  stress.beta = 10.0;
  const double factor = stiffness_factor(stress, DemParams().max_overlap);
  ASSERT_GT(factor, 2.0);
  // The stress law's limit is the classical one over sqrt(allowance), to the bisection's width.
  EXPECT_NEAR(largest_accepted_dt<Exec>(h, box, &stress) * std::sqrt(factor) / classical, 1.0,
              1e-9);
  // MC-strain adds no instantaneous stiffness (its run-time overlap check covers it).
  const MultiContact strain = law(MultiContact::Strain);
  EXPECT_NEAR(largest_accepted_dt<Exec>(h, box, &strain) / classical, 1.0, 1e-9);
  // The refusal says why.
  DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), box, frictionless(),
                             params(0.9 * classical));
  try {
    sys.set_multicontact(stress);
    ADD_FAILURE() << "dt above the MC-stress limit accepted";
  } catch (const PhysicsError& e) {
    EXPECT_NE(std::string(e.what()).find("MC-stress"), std::string::npos) << e.what();
  }
}

TYPED_TEST(MultiContactTest, StrainCorrectedOverlapBeyondTheLimitStopsTheRun) {
  using Exec = TypeParam;
  // Three spheres in a row, each contact at 0.2 a: the middle one's opposite contacts press
  // each other deeper under MC-strain. Below the limit the state passes; with the limit
  // between the geometric and the corrected overlap, it stops, naming MC-strain.
  const double delta = 0.2 * kA;
  const HostParticles h = particles(
      {{0, 0, 0, kA, 0}, {2 * kA - delta, 0, 0, kA, 0}, {4 * kA - 2 * delta, 0, 0, kA, 0}});
  const PeriodicBox box = open_box(-5 * kA, 10 * kA);
  MultiContact mc = law(MultiContact::Strain);
  mc.gamma = 5.0;
  for (const double limit : {0.6, 0.21}) {
    DemParams prm = params();
    prm.max_overlap = limit;
    DemSystem<Exec, Hertz> sys(Particles<Exec>::from_host(h), box, frictionless(), prm);
    sys.set_multicontact(mc);
    const Measurements m = sys.measure();
    ASSERT_NEAR(m.max_overlap, 0.2, 1e-9);
    if (limit > 0.5) {
      EXPECT_NO_THROW(sys.check_health(m));
    } else {
      try {
        sys.check_health(m);
        ADD_FAILURE() << "corrected overlap beyond the limit passed";
      } catch (const PhysicsError& e) {
        EXPECT_NE(std::string(e.what()).find("MC-strain's corrected overlap"), std::string::npos)
            << e.what();
      }
    }
  }
}
