// Closed forms an impact is measured against (docs/contact_laws.md): elastic Hertz for the
// normal direction, and rigid-body gross sliding for the tangential one. Shared by the
// `impact` and `impact_benchmarks` scenes and the tests.
#pragma once
#include <cmath>

namespace granular {

// Elastic Hertz impact at normal speed v: duration, largest overlap and force, with E*, R*
// and m* of the contact (a wall: R* = a, m* = m).
struct HertzClosedForm {
  double duration, overlap, force;
};
inline HertzClosedForm hertz_closed_form(double estar, double rstar, double mstar, double v) {
  const double kh = 4.0 / 3.0 * estar * std::sqrt(rstar);
  const double dmax = std::pow(1.25 * mstar * v * v / kh, 0.4);
  // t_c = (2 delta_max / v) Int_0^1 (1 - x^{5/2})^{-1/2} dx = 2.94 delta_max / v
  const double integral = std::tgamma(0.4) * std::tgamma(0.5) / std::tgamma(0.9) / 2.5;
  return {2.0 * dmax / v * integral, dmax, kh * std::pow(dmax, 1.5)};
}

// Gross sliding of two solid spheres (or a sphere on a wall: m2 = inf) whose contact point
// slides through the whole impact: the tangential impulse is mu (1 + e) m* v_n against the
// slip, and the slip velocity changes by (7/2) mu (1 + e) v_n (each sphere's
// 1/m + R^2/I = 7/(2 m)). It slides throughout when |v_c| > (7/2) mu (1 + e) v_n.
// Sphere 1 moves along -z onto the contact below it; x is the tangent; spins about y.
struct GrossSliding {
  bool slides = false;
  double impulse_ratio = 0;           // J_t / J_n (signed: positive along the slip's opposite)
  double vt1_out = 0;                 // sphere 1's tangential (x) velocity after the impact
  double spin1_out = 0;               // sphere 1's spin about y after the impact
  double vc_out = 0;                  // slip velocity of the contact points after the impact
  double restitution_tangential = 0;  // -v_c,out / v_c,in
};
inline GrossSliding gross_sliding(double m1, double a1, double mstar, double vn, double vt1,
                                  double spin1, double vc, double mu, double e) {
  GrossSliding g;
  const double dvc = 3.5 * mu * (1 + e) * vn;
  g.slides = std::fabs(vc) > dvc;
  const double sgn = vc >= 0 ? 1.0 : -1.0;
  const double jt = -sgn * mu * (1 + e) * mstar * vn;  // on sphere 1, along x
  g.impulse_ratio = sgn * mu;
  g.vt1_out = vt1 + jt / m1;
  g.spin1_out = spin1 - 2.5 * jt / (m1 * a1);  // torque of f_t x at lever -a1 z: -a1 f_t y
  g.vc_out = vc - sgn * dvc;
  g.restitution_tangential = vc != 0 ? -g.vc_out / vc : 0.0;
  return g;
}

}  // namespace granular
