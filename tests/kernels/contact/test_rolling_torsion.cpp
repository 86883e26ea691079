// Rolling and torsion resistance (docs/model_dem.md §3) against closed forms.
// Law level: a pair held at fixed overlap with an imposed relative spin. The rolling
// (torsion) displacement grows as a' w t, the torque on i is -k a'^2 w t until the Coulomb
// cap a' mu f_n, then stays there; reversing the spin unloads along the same stiffness.
// Dynamics: in a head-on collision the relative spin is a harmonic oscillator of angular
// frequency a' sqrt(k (1/I_i + 1/I_j)) that runs for exactly the contact duration, and the
// total spin angular momentum is conserved because the torques on i and j are opposite.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

namespace {

using Rolling = ContactModel<LinearNormal, NoTangential, RollingTorsion>;

constexpr double kInf = std::numeric_limits<double>::infinity();

// A pair along x (n = +x from j to i) with the given overlap and relative spin.
PairState resting_pair(double ai, double aj, double delta, const double wrel[3]) {
  PairState s{};
  s.n[0] = 1, s.n[1] = 0, s.n[2] = 0;
  s.delta = delta, s.delta_dot = 0;
  s.ai = ai, s.aj = aj, s.mstar = 1.0;
  s.si = s.sj = 0, s.wall = false;
  for (int d = 0; d < 3; ++d) s.vt[d] = 0, s.wrel[d] = wrel[d];
  return s;
}

// Imposes the relative spin w about `axis` (0: x, along the normal = torsion; 2: z, in the
// tangent plane = rolling) for `steps` steps from the history h and checks the torque on i
// (component along `axis`, which is where rolling about z and torsion about x put it)
// against min(k a'^2 |theta|, a' mu f_n) with the sign opposing the relative rotation.
// Returns the torque of the last step.
double drive(const Rolling& model, int axis, double w, double dt, int steps, double theta0,
             double k, double mu, double* h) {
  const double ai = 1.0, aj = 0.6, delta = 2e-3;
  const double ar = ai * aj / (ai + aj);
  double wrel[3] = {0, 0, 0};
  wrel[axis] = w;
  const PairState s = resting_pair(ai, aj, delta, wrel);
  const double fn = model.normal.table(0, 0).kn * delta;
  const double cap = ar * mu * fn;
  double theta = theta0;  // relative rotation angle, with the spring's slip folded in
  double q = 0;
  for (int step = 0; step < steps; ++step) {
    PairForce out;
    model.evaluate(s, dt, h, out);
    theta += w * dt;
    double expected = -k * ar * ar * theta;
    if (std::fabs(expected) > cap) {  // sliding: the spring is shortened to the cap
      expected = std::copysign(cap, expected);
      theta = expected / (-k * ar * ar);
    }
    // The spring is a running sum of a' w dt: a few ulps per step, so 1e-12 relative after
    // a few hundred steps is ample and still far below any modelling error.
    EXPECT_NEAR(out.q[axis], expected, 1e-12 * cap) << "step " << step;
    EXPECT_EQ(out.qj[axis], -out.q[axis]);  // action = reaction, exactly
    for (int d = 0; d < 3; ++d) EXPECT_EQ(d == axis ? 0.0 : out.q[d], 0.0) << d;
    EXPECT_DOUBLE_EQ(out.fn, fn);
    q = out.q[axis];
  }
  return q;
}

}  // namespace

TEST(RollingTorsionLaw, RollingTorqueIsSpringUpToCoulombCapThenConstantAndUnloadsElastically) {
  const double kn = 1e5, kr = 3e4, mur = 0.05;
  const Rolling model{
      LinearNormal::uniform(kn, 0), {}, RollingTorsion::uniform({kr, 0, mur, 0, 0, kInf})};
  double h[Rolling::history] = {};
  const double ar = 0.375, fn = kn * 2e-3, dt = 1e-2, w = 1e-3;
  // Cap reached after mu fn / (kr a' w dt) steps ~ 89: drive well past it.
  const int to_cap = static_cast<int>(std::ceil(mur * fn / (kr * ar * w * dt)));
  ASSERT_LT(to_cap, 150);
  const double q = drive(model, 2, w, dt, 200, 0.0, kr, mur, h);
  EXPECT_NEAR(std::fabs(q), ar * mur * fn, 1e-12 * ar * mur * fn);
  // The spring holds exactly the elongation that gives the capped force: |s_r| = mu fn / kr.
  EXPECT_NEAR(std::hypot(h[0], h[1], h[2]), mur * fn / kr, 1e-12 * mur * fn / kr);
  // Reverse the spin: the torque unloads along kr a'^2 from the cap, then caps on the other
  // side (theta restarts at the capped spring's angle).
  drive(model, 2, -w, dt, 250, mur * fn / (kr * ar), kr, mur, h);
}

TEST(RollingTorsionLaw, TorsionTorqueIsSpringUpToCoulombCapThenConstant) {
  const double kn = 1e5, ko = 5e4, muo = 0.02;
  const Rolling model{
      LinearNormal::uniform(kn, 0), {}, RollingTorsion::uniform({0, 0, kInf, ko, 0, muo})};
  double h[Rolling::history] = {};
  const double ar = 0.375, fn = kn * 2e-3, dt = 1e-2, w = -2e-3;
  const double q = drive(model, 0, w, dt, 100, 0.0, ko, muo, h);
  EXPECT_NEAR(q, ar * muo * fn, 1e-12 * ar * muo * fn);  // w < 0: the torque is positive
  // The torsion spring lies along the normal only; the rolling spring stayed empty.
  EXPECT_EQ(h[0], 0.0);
  EXPECT_EQ(h[4], 0.0);
  EXPECT_NEAR(std::fabs(h[3]), muo * fn / ko, 1e-12 * muo * fn / ko);
}

TEST(RollingTorsionLaw, ViscousPartOpposesRelativeRotationWithLeverArmSquared) {
  // One step from an empty spring: torque = -a'^2 (k w dt + g w), both terms on the lever
  // a' twice (velocity a' w, torque a' f).
  const double kr = 3e4, gr = 40, ko = 5e4, go = 25;
  const Rolling model{
      LinearNormal::uniform(1e5, 0), {}, RollingTorsion::uniform({kr, gr, kInf, ko, go, kInf})};
  const double ar = 0.375, dt = 1e-2, w = 1e-3;
  const double wrel[3] = {w, 0, w};  // twist and roll at once
  const PairState s = resting_pair(1.0, 0.6, 2e-3, wrel);
  double h[Rolling::history] = {};
  PairForce out;
  model.evaluate(s, dt, h, out);
  // A handful of roundings: 1e-14 relative.
  const double qo = -ar * ar * (ko * w * dt + go * w), qr = -ar * ar * (kr * w * dt + gr * w);
  EXPECT_NEAR(out.q[0], qo, 1e-14 * std::fabs(qo));
  EXPECT_NEAR(out.q[2], qr, 1e-14 * std::fabs(qr));
  EXPECT_EQ(out.q[1], 0.0);
}

namespace {

double mass(double a) { return 2000.0 * 4.0 / 3.0 * M_PI * a * a * a; }

struct SpinResult {
  double wrel_before = 0, wrel_after = 0;  // relative spin about the axis
  double L_before = 0, L_after = 0;        // total spin angular momentum about the axis
  double tc = 0;
};

// Head-on collision along x of spheres of radii 1 and 0.7; sphere 1 spins at w0 about
// `axis` (0: along the normal, torsion; 2: perpendicular, rolling). No tangential law, so
// the centres move along x only and the normal never turns.
template <class Exec>
SpinResult spin_collision(const Rolling& model, int axis, double w0, double dt) {
  const double a1 = 1.0, a2 = 0.7, speed = 1e-3, sum = a1 + a2, edge = 8 * sum;
  HostParticles h;
  h.resize(2);
  h.x = {0.5 * edge - 0.5 * sum - 5 * speed * dt, 0.5 * edge + 0.5 * sum};
  h.y = {0.5 * edge, 0.5 * edge}, h.z = {0.5 * edge, 0.5 * edge};
  h.vx = {speed, 0.0};
  h.radius = {a1, a2}, h.density = {2000, 2000};
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = edge;
  DemParams prm;
  prm.dt = dt, prm.skin = 0.1 * sum, prm.max_overlap = 1.0, prm.sort = false;
  DemSystem<Exec, Rolling> sys(Particles<Exec>::from_host(h), box, model, prm);
  auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().w);
  auto inertia = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().inertia);
  w(0, axis) = w0;
  Kokkos::deep_copy(sys.particles().w, w);
  sys.refresh_forces();
  SpinResult r;
  r.wrel_before = w0;
  r.L_before = inertia(0) * w0;
  const double m = mass(a1) * mass(a2) / (mass(a1) + mass(a2));
  r.tc = model.normal.contact_duration(m);
  // Until well after separation (5 steps of approach, t_c, then 50 steps apart).
  sys.step(static_cast<long>(r.tc / dt) + 60);
  Kokkos::deep_copy(w, sys.particles().w);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
  EXPECT_GT(std::fabs(x(1, 0) - x(0, 0)), sum) << "still in contact";
  r.wrel_after = w(0, axis) - w(1, axis);
  r.L_after = inertia(0) * w(0, axis) + inertia(1) * w(1, axis);
  return r;
}

}  // namespace

template <class T>
class RollingTorsionDynamics : public ::testing::Test {};
TYPED_TEST_SUITE(RollingTorsionDynamics, granular::testing::ExecSpaces);

TYPED_TEST(RollingTorsionDynamics, RelativeSpinOscillatesAtSpringFrequencyDuringContact) {
  const double kn = 1e5, k = 6e4, a1 = 1.0, a2 = 0.7, ar = a1 * a2 / (a1 + a2);
  const double I1 = 0.4 * mass(a1) * a1 * a1, I2 = 0.4 * mass(a2) * a2 * a2;
  const double omega = ar * std::sqrt(k * (1 / I1 + 1 / I2));
  for (int axis : {0, 2}) {
    const RollingTorsion::Params p =
        axis == 0 ? RollingTorsion::Params{0, 0, kInf, k, 0, kInf}   // torsion only
                  : RollingTorsion::Params{k, 0, kInf, 0, 0, kInf};  // rolling only
    const Rolling model{LinearNormal::uniform(kn, 0), {}, RollingTorsion::uniform(p)};
    const double m = mass(a1) * mass(a2) / (mass(a1) + mass(a2));
    const double tc = model.normal.contact_duration(m);
    ASSERT_GT(omega * tc, 1.5);  // a good part of a period: the phase is measured, not assumed
    ASSERT_LT(omega * tc, 3.0);
    const SpinResult r = spin_collision<TypeParam>(model, axis, 2e-3, tc / 4000);
    // Contact start and end are resolved to one step, so the phase is known to within
    // omega dt ~ 6e-4 rad; the Verlet error is O((omega dt)^2). 2e-3 covers both.
    EXPECT_NEAR(r.wrel_after / r.wrel_before, std::cos(omega * tc), 2e-3) << "axis " << axis;
    // Opposite torques on i and j: spin angular momentum about the axis is conserved to
    // round-off (the orbital part is zero: centres move along x, spins are along x or z
    // through the centres).
    EXPECT_NEAR(r.L_after, r.L_before, 1e-12 * std::fabs(r.L_before)) << "axis " << axis;
  }
}

TYPED_TEST(RollingTorsionDynamics, SpinningSphereOnWallStopsUnderCappedResistanceThenIsHeld) {
  // A sphere resting on a floor under gravity (exact static overlap m g / k_n, so f_n = m g
  // throughout) spins about a tangent axis (rolling) or about the normal (torsion). With
  // no tangential law the centre stays put; the spring loads within t_s = mu f_n/(k a w0),
  // then the torque is the Coulomb cap a mu f_n (a wall has infinite radius: a' = a), so
  // the spin decays linearly, w(t) = w0 - alpha (t - t_s/2), alpha = a mu f_n / I, and stops
  // at t* = t_s/2 + w0/alpha. Afterwards the unloaded spring holds the sphere: it swings
  // elastically with spin amplitude at most alpha / omega_k, omega_k = a sqrt(k / I).
  using Exec = TypeParam;
  const double a = 1.0, kn = 1e5, g = 0.1, k = 1e6, mu = 0.1, w0 = 0.01, dt = 1e-4;
  const double m = mass(a), I = 0.4 * m * a * a, fn = m * g;
  const double alpha = a * mu * fn / I, ts = mu * fn / (k * a * w0);
  const double tstop = 0.5 * ts + w0 / alpha, omega_k = a * std::sqrt(k / I);
  ASSERT_LT(ts, 0.05 * tstop);  // the loading phase is short against the decay
  for (int axis : {0, 2}) {
    const RollingTorsion::Params p = axis == 0 ? RollingTorsion::Params{k, 0, mu, 0, 0, kInf}
                                               : RollingTorsion::Params{0, 0, kInf, k, 0, mu};
    const Rolling model{LinearNormal::uniform(kn, 0), {}, RollingTorsion::uniform(p)};
    HostParticles h;
    h.resize(1);
    h.x[0] = 0, h.y[0] = 0, h.z[0] = a - m * g / kn, h.radius[0] = a, h.density[0] = 2000;
    PeriodicBox box;
    for (int d = 0; d < 3; ++d) box.lo[d] = -5, box.len[d] = 10, box.periodic[d] = false;
    DemParams prm;
    prm.dt = dt, prm.skin = 0.1, prm.gravity[2] = -g;
    DemSystem<Exec, Rolling> sys(Particles<Exec>::from_host(h), box, model, prm);
    WallSpec floor;
    floor.normal[2] = -1;
    sys.set_walls({floor});
    auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().w);
    w(0, axis) = w0;
    Kokkos::deep_copy(sys.particles().w, w);
    sys.refresh_forces();
    double held = 0;
    const long nsteps = static_cast<long>(2 * tstop / dt);
    for (long n = 1; n <= nsteps; ++n) {
      sys.step(1);
      const double t = n * dt;
      if (n % 100 != 0 && t < tstop + 0.1) continue;
      Kokkos::deep_copy(w, sys.particles().w);
      if (t > ts && t < tstop - 10 * dt) {
        // Per-step sampling of the torque shifts the decay by at most alpha dt (2.5e-6
        // here); the loading phase deviates from the linear ramp by O((omega_k t_s)^2)
        // of its impulse, below 1e-6. Hence 1e-3 w0 = 1e-5.
        EXPECT_NEAR(w(0, axis), w0 - alpha * (t - 0.5 * ts), 1e-3 * w0) << "axis " << axis;
      } else if (t > tstop + 0.1) {
        held = std::max(held, std::fabs(w(0, axis)));
      }
      for (int d = 0; d < 3; ++d) EXPECT_EQ(d == axis ? 0.0 : w(0, d), 0.0) << d;
    }
    EXPECT_GT(held, 0.0);  // it does swing after stopping
    EXPECT_LE(held, 1.01 * alpha / omega_k) << "axis " << axis;
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
    EXPECT_NEAR(x(0, 0), 0.0, 1e-12);  // no tangential force: the centre never moved
    EXPECT_NEAR(x(0, 1), 0.0, 1e-12);
  }
}
