// The engine's own restitution-damped Hertz-Mindlin law against LAMMPS' `pair_style granular
// hertz/material ... damping tsuji tangential mindlin` (scenarios/lammps/native_laws.hpp), pair
// by pair: the LAMMPS side is the `lammps_forces` reference, which tests/lammps/ compares with
// LAMMPS itself to round-off. Both sides see the same two spheres; the engine's side goes
// through the pair geometry of its force loop (pair_geometry) and the model's evaluate.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/lammps/lammps_pair_styles.hpp"
#include "core/run/error.hpp"
#include "kernels/dem/contact_forces.hpp"
#include "scenarios/lammps/native_laws.hpp"

using namespace granular;

namespace {

const char* kPair =
    "* * hertz/material 7.0e10 0.8 0.25 tangential mindlin NULL 0.7 0.4 damping tsuji";
constexpr double kDensity = 2500.0, kDt = 1e-7;

GranularPair tsuji_pair(const std::string& coeff = kPair) {
  return parse_lammps_pair("granular", {coeff}, 1, lammps_units("si")).pair(1, 1);
}

struct Sphere {
  double x[3], v[3], w[3], r;
  double mass() const { return kDensity * 4.0 / 3.0 * M_PI * r * r * r; }
};

struct Both {
  LammpsContactOut lammps;
  PairForce engine;
};

// One step of the pair (i, j) on both sides, each advancing its own spring.
Both evaluate(const LammpsPairModel& lm, const NativeHertzTsuji& model, const Sphere& i,
              const Sphere& j, double* h_lammps, double* h_engine) {
  Both out;
  double del[3];
  for (int d = 0; d < 3; ++d) del[d] = i.x[d] - j.x[d];
  const double rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
  const LammpsContactIn in{
      {del[0], del[1], del[2]}, rsq, i.v, j.v, i.w, j.w, i.r, j.r, i.mass(), j.mass(), 1, 1};
  lammps_contact(lm, in, kDt, true, h_lammps, out.lammps);
  Body bi{}, bj{};
  for (int d = 0; d < 3; ++d) {
    bi.x[d] = i.x[d], bi.v[d] = i.v[d], bi.w[d] = i.w[d];
    bj.x[d] = j.x[d], bj.v[d] = j.v[d], bj.w[d] = j.w[d];
  }
  bi.a = i.r, bj.a = j.r, bi.m = i.mass(), bj.m = j.mass(), bi.s = bj.s = 0;
  const double rate[3] = {0, 0, 0};
  PairState s;
  pair_geometry(bi, bj, del[0], del[1], del[2], rsq, rate, true, s);
  model.evaluate(s, kDt, h_engine, out.engine);
  return out;
}

double norm(const double* a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

// Largest component difference of force and both torques, relative to the force's size
// (torques to force times the larger radius).
double mismatch(const Both& b, double r) {
  const double f = norm(b.lammps.f);
  double e = 0;
  for (int d = 0; d < 3; ++d) {
    e = std::max(e, std::fabs(b.engine.f[d] - b.lammps.f[d]) / f);
    e = std::max(e, std::fabs(b.engine.q[d] - b.lammps.torque_i[d]) / (f * r));
    e = std::max(e, std::fabs(b.engine.qj[d] - b.lammps.torque_j[d]) / (f * r));
  }
  return e;
}

// A random pair in contact, i above j along a random direction, no spin.
std::pair<Sphere, Sphere> random_pair(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Sphere i{}, j{};
  i.r = 0.5e-3 + 1e-3 * u(rng), j.r = 0.5e-3 + 1e-3 * u(rng);
  // Overlaps from 1e-5 to 3e-2 of the smaller radius, evenly in log: light contacts slide.
  const double delta = std::pow(10.0, -5 + 3.5 * u(rng)) * std::min(i.r, j.r);
  const double ct = 2 * u(rng) - 1, ph = 2 * M_PI * u(rng), st = std::sqrt(1 - ct * ct);
  const double n[3] = {st * std::cos(ph), st * std::sin(ph), ct};
  const double dist = i.r + j.r - delta;
  for (int d = 0; d < 3; ++d) {
    j.x[d] = 0.01;
    i.x[d] = 0.01 + dist * n[d];
    i.v[d] = 0.4 * (2 * u(rng) - 1), j.v[d] = 0.4 * (2 * u(rng) - 1);
  }
  return {i, j};
}

}  // namespace

TEST(NativeLaws, HertzMaterialTsujiMindlinWithoutSpinIsTheEngineLawToRoundOff) {
  const GranularPair p = tsuji_pair();
  const LammpsPairModel lm = parse_lammps_pair("granular", {kPair}, 1, lammps_units("si"));
  const NativeHertzTsuji model = native_hertz_tsuji(p, 1.0);
  std::mt19937_64 rng(20261129);
  int stuck = 0, slid = 0;
  for (int k = 0; k < 400; ++k) {
    auto [i, j] = random_pair(rng);
    double hl[3] = {0, 0, 0}, he[3] = {0, 0, 0};
    const Both b = evaluate(lm, model, i, j, hl, he);
    EXPECT_LT(mismatch(b, std::max(i.r, j.r)), 1e-12) << "pair " << k;
    // Both regimes must be covered: sliding caps |f_t| at mu |f_n|.
    (norm(b.engine.ft) < p.mu * std::fabs(b.engine.fn) * (1 - 1e-9) ? stuck : slid) += 1;
  }
  EXPECT_GE(stuck, 40);
  EXPECT_GE(slid, 40);
}

TEST(NativeLaws, SpringsOfBothLawsAgreeOverManyStepsOfAMovingPair) {
  const LammpsPairModel lm = parse_lammps_pair("granular", {kPair}, 1, lammps_units("si"));
  const NativeHertzTsuji model = native_hertz_tsuji(tsuji_pair(), 1.0);
  const double mu = tsuji_pair().mu;
  std::mt19937_64 rng(7);
  int long_lived = 0;
  for (int k = 0; k < 20; ++k) {
    auto [i, j] = random_pair(rng);
    // Slow enough to stick for most of the steps: the spring's history then decides the force.
    for (int d = 0; d < 3; ++d) i.v[d] *= 0.01, j.v[d] *= 0.01;
    double hl[3] = {0, 0, 0}, he[3] = {0, 0, 0};
    int step = 0;
    for (; step < 200; ++step) {
      double gap = 0;
      for (int d = 0; d < 3; ++d) gap += (i.x[d] - j.x[d]) * (i.x[d] - j.x[d]);
      if (std::sqrt(gap) >= i.r + j.r) break;  // apart: both codes forget the spring
      const Both b = evaluate(lm, model, i, j, hl, he);
      // LAMMPS leaves the spring out of the plane by up to 1e-10 of the sliding limit before
      // turning it; the engine turns it every step.
      ASSERT_LT(mismatch(b, std::max(i.r, j.r)), 1e-9) << "pair " << k << " step " << step;
      // After a slip the springs differ by design (native_laws.hpp): compare sticking only.
      if (!(norm(b.engine.ft) < mu * std::fabs(b.engine.fn) * (1 - 1e-9))) break;
      for (int d = 0; d < 3; ++d) i.x[d] += i.v[d] * kDt, j.x[d] += j.v[d] * kDt;
    }
    if (step >= 100) ++long_lived;
  }
  EXPECT_GE(long_lived, 10);  // the history of most pairs was compared over 100+ steps
}

TEST(NativeLaws, SpinEntersTheEngineThroughLeverArmsShorterByHalfTheOverlap) {
  const LammpsPairModel lm = parse_lammps_pair("granular", {kPair}, 1, lammps_units("si"));
  const NativeHertzTsuji model = native_hertz_tsuji(tsuji_pair(), 1.0);
  // Pair along z, no relative translation, both spinning about x at the same rate: the
  // contact points move along y at (l_i + l_j) w (engine) or (r_i + r_j) w (LAMMPS).
  Sphere i{}, j{};
  i.r = 1e-3, j.r = 0.7e-3;
  const double delta = 4e-6;
  i.x[2] = i.r + j.r - delta;
  i.w[0] = j.w[0] = 0.3;
  double hl[3] = {0, 0, 0}, he[3] = {0, 0, 0};
  const Both b = evaluate(lm, model, i, j, hl, he);
  ASSERT_GT(std::fabs(b.lammps.f[1]), 0.0);
  const double expected = (i.r + j.r - delta) / (i.r + j.r);
  EXPECT_NEAR(b.engine.f[1] / b.lammps.f[1], expected, 1e-12);
  EXPECT_NEAR(b.engine.f[2], b.lammps.f[2], 1e-12 * std::fabs(b.lammps.f[2]));
}

TEST(NativeLaws, OnlyHertzMaterialWithTsujiAndMindlinMapsToTheNativeLaw) {
  EXPECT_THROW(native_hertz_tsuji(tsuji_pair("* * hertz/material 7e10 0.1 0.25 tangential "
                                             "mindlin NULL 0.7 0.4 damping viscoelastic"),
                                  1.0),
               InputError);
  EXPECT_THROW(native_hertz_tsuji(tsuji_pair("* * hertz 1e9 0.8 tangential mindlin 1e9 0.7 0.4 "
                                             "damping tsuji"),
                                  1.0),
               InputError);
  EXPECT_THROW(native_hertz_tsuji(tsuji_pair(std::string(kPair) + " limit_damping"), 1.0),
               InputError);
  EXPECT_NO_THROW(native_hertz_tsuji(tsuji_pair(), 1e-6));
}
