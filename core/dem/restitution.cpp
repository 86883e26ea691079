#include "core/dem/restitution.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace granular {

namespace {

// Right-hand side of x'' = -alpha x^{1/4} x' - x^{3/2}; no force once the spheres part
// (x <= 0), which the last step of a collision may probe.
struct Collision {
  double alpha;
  void operator()(double x, double v, double& dx, double& dv) const {
    dx = v;
    if (x <= 0.0) {
      dv = 0.0;
      return;
    }
    const double r = std::sqrt(x);
    dv = -alpha * std::sqrt(r) * v - x * r;
  }
};

// One Dormand-Prince 5(4) step of length h from (x, v): the fifth-order result and the
// difference to the embedded fourth-order one.
void dopri_step(const Collision& f, double x, double v, double h, double& x5, double& v5,
                double& ex, double& ev) {
  constexpr double a21 = 1.0 / 5;
  constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
  constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
  constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                   a54 = -212.0 / 729;
  constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                   a65 = -5103.0 / 18656;
  constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784,
                   b6 = 11.0 / 84;
  // Fifth minus fourth order weights (the seventh stage is the FSAL one at the new point).
  constexpr double d1 = 71.0 / 57600, d3 = -71.0 / 16695, d4 = 71.0 / 1920, d5 = -17253.0 / 339200,
                   d6 = 22.0 / 525, d7 = -1.0 / 40;
  double kx[7], kv[7];
  f(x, v, kx[0], kv[0]);
  f(x + h * a21 * kx[0], v + h * a21 * kv[0], kx[1], kv[1]);
  f(x + h * (a31 * kx[0] + a32 * kx[1]), v + h * (a31 * kv[0] + a32 * kv[1]), kx[2], kv[2]);
  f(x + h * (a41 * kx[0] + a42 * kx[1] + a43 * kx[2]),
    v + h * (a41 * kv[0] + a42 * kv[1] + a43 * kv[2]), kx[3], kv[3]);
  f(x + h * (a51 * kx[0] + a52 * kx[1] + a53 * kx[2] + a54 * kx[3]),
    v + h * (a51 * kv[0] + a52 * kv[1] + a53 * kv[2] + a54 * kv[3]), kx[4], kv[4]);
  f(x + h * (a61 * kx[0] + a62 * kx[1] + a63 * kx[2] + a64 * kx[3] + a65 * kx[4]),
    v + h * (a61 * kv[0] + a62 * kv[1] + a63 * kv[2] + a64 * kv[3] + a65 * kv[4]), kx[5], kv[5]);
  x5 = x + h * (b1 * kx[0] + b3 * kx[2] + b4 * kx[3] + b5 * kx[4] + b6 * kx[5]);
  v5 = v + h * (b1 * kv[0] + b3 * kv[2] + b4 * kv[3] + b5 * kv[4] + b6 * kv[5]);
  f(x5, v5, kx[6], kv[6]);
  ex = h * (d1 * kx[0] + d3 * kx[2] + d4 * kx[3] + d5 * kx[4] + d6 * kx[5] + d7 * kx[6]);
  ev = h * (d1 * kv[0] + d3 * kv[2] + d4 * kv[3] + d5 * kv[4] + d6 * kv[5] + d7 * kv[6]);
}

// Local error tolerance per step (absolute: x and x' are of order 1, the impact speed).
// The error of e scales with it (measured against the closed form of restitution.hpp over
// alpha in [0, sqrt(5)]: 3e-9 at 1e-12, 3e-10 at 1e-13, 3e-11 at 1e-14, 3e-12 at 1e-15),
// so the integration is converged; at 1e-15 e is good to 3e-12 absolute and 2e-10 relative
// for e > 1e-3, in 0.15 ms per call.
constexpr double kTolerance = 1e-15;

}  // namespace

double hertz_restitution_of_alpha(double alpha) {
  if (!(alpha >= 0.0) || !std::isfinite(alpha))
    throw std::invalid_argument("hertz_restitution_of_alpha: alpha must be finite and >= 0");
  const Collision f{alpha};
  double t = 0.0, x = 0.0, v = 1.0;
  double h = 1e-3;
  // The elastic collision lasts 3.22 time units; an overdamped one creeps as t^{-4} towards
  // x = 0 without reaching it. Past this time (or once the return speed is negligible) the
  // spheres count as stuck.
  constexpr double t_max = 1e4;
  for (long steps = 0; steps < 10000000 && t < t_max; ++steps) {
    double x5, v5, ex, ev;
    dopri_step(f, x, v, h, x5, v5, ex, ev);
    const double err = std::max(std::fabs(ex), std::fabs(ev)) / kTolerance;
    if (err > 1.0) {  // reject, shrink
      h *= std::max(0.1, 0.9 * std::pow(err, -0.2));
      continue;
    }
    if (x5 <= 0.0 && t > 0.0) {
      // The overlap closes within this step: find the step length that lands on x = 0
      // (regula falsi, Illinois variant, on the fifth-order step map).
      double lo = 0.0, hi = h, x_lo = x, x_hi = x5, v_end = v5;
      int side = 0;
      for (int it = 0; it < 200 && hi - lo > 1e-15 * (1.0 + t); ++it) {
        const double m = (lo * x_hi - hi * x_lo) / (x_hi - x_lo);
        double xm, vm, exm, evm;
        dopri_step(f, x, v, m, xm, vm, exm, evm);
        v_end = vm;
        if (xm == 0.0) {
          lo = hi = m;
          break;
        }
        if (xm > 0.0) {
          lo = m, x_lo = xm;
          if (side == 1) x_hi *= 0.5;
          side = 1;
        } else {
          hi = m, x_hi = xm;
          if (side == -1) x_lo *= 0.5;
          side = -1;
        }
      }
      return std::max(0.0, -v_end);
    }
    t += h, x = x5, v = v5;
    h *= std::min(5.0, 0.9 * std::pow(std::max(err, 1e-10), -0.2));
  }
  return 0.0;
}

double hertz_alpha_exact(double e) {
  if (!(e > 0.0 && e <= 1.0))
    throw std::invalid_argument("hertz_alpha_exact: restitution must lie in (0, 1]");
  if (e == 1.0) return 0.0;
  // e(alpha) decreases from 1 at 0 to 0 at sqrt(5): bisect on [0, sqrt(5)].
  double lo = 0.0, hi = std::sqrt(5.0);
  while (hi - lo > 1e-14) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (hertz_restitution_of_alpha(mid) > e ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double restitution_beta(double e) {
  if (!(e >= 0.0 && e <= 1.0))
    throw std::invalid_argument("restitution_beta: restitution must lie in [0, 1]");
  if (e == 0.0) return 1.0;
  const double l = std::log(e);
  return -l / std::sqrt(l * l + M_PI * M_PI);
}

double hertz_alpha_common(double e) { return std::sqrt(5.0) * restitution_beta(e); }

double mindlin_gt_common(double e) { return 2.0 * std::sqrt(5.0 / 6.0) * restitution_beta(e); }

double effective_young(double E_i, double nu_i, double E_j, double nu_j) {
  return 1.0 / ((1.0 - nu_i * nu_i) / E_i + (1.0 - nu_j * nu_j) / E_j);
}

double effective_shear(double G_i, double nu_i, double G_j, double nu_j) {
  return 1.0 / ((2.0 - nu_i) / G_i + (2.0 - nu_j) / G_j);
}

}  // namespace granular
