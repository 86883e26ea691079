// Restitution-parameterised Hertz(-Mindlin) damping (docs/model_dem.md §10), host side.
//
// Normal force f = k_H delta^{3/2} + eta delta^{1/4} d(delta)/dt, k_H = (4/3) E* sqrt(R*),
// eta = alpha sqrt(m* k_H). With delta = delta_0 x, t = tau s, delta_0 = v tau and
// tau = (m*/k_H)^{2/5} v^{-1/5} the collision becomes
//     x'' + alpha x^{1/4} x' + x^{3/2} = 0,   x(0) = 0, x'(0) = 1,
// which contains neither the impact speed v nor any material constant: the coefficient of
// restitution e = -x'(end) is a function of alpha alone.
//
// That function is known in closed form. In the time sigma with d(sigma) = x^{1/4} ds and
// for z = x^{5/4} the equation becomes the linear oscillator
//     z_sigma_sigma + alpha z_sigma + (5/4) z = 0,
// and x' = (4/5) z_sigma, so the restitution is that of a linear oscillator with damping
// ratio zeta = alpha / sqrt(5):  e = exp(-pi zeta / sqrt(1 - zeta^2)), alpha = sqrt(5) beta(e)
// below. There is no rebound for alpha >= sqrt(5) (zeta >= 1): the spheres creep apart as
// x ~ s^{-4} and never separate. The numerical route below is kept as the definition the
// tests check that identity with (and as the template for damping forms without one).
//
// Nothing here includes Kokkos: model setup and tests call it on the host.
#pragma once

namespace granular {

// e(alpha): the dimensionless collision integrated with an adaptive Dormand-Prince 5(4)
// scheme to the return of x to 0 (the crossing located within the step). Accurate to
// ~3e-12 absolute. Returns 0 where the collision never ends (alpha >= sqrt(5), the
// overdamped limit). Throws std::invalid_argument for a negative or non-finite alpha.
double hertz_restitution_of_alpha(double alpha);

// The inverse alpha(e) for e in (0, 1], by bisection of hertz_restitution_of_alpha on
// [0, sqrt(5)] (alpha(1) = 0, decreasing in e). About 7 ms. Throws std::invalid_argument
// outside (0, 1].
double hertz_alpha_exact(double e);

// beta(e) = -ln e / sqrt(ln^2 e + pi^2), the damping ratio of a linear oscillator that
// rebounds with restitution e; beta(0) = 1, beta(1) = 0. e in [0, 1], else throws.
double restitution_beta(double e);

// The mapping most DEM codes use (Tsuji-type damping with the linear-oscillator beta):
//   gamma_n = 2 sqrt(5/6) beta sqrt(S_n m*),  S_n = 2 E* sqrt(R* delta).
// Written as eta delta^{1/4} d(delta)/dt with eta = alpha sqrt(m* k_H), k_H = (4/3) E* sqrt(R*):
//   eta = 2 sqrt(5/6) beta sqrt(2 E* sqrt(R*) m*) = 2 sqrt(5/6) sqrt(3/2) beta sqrt(m* k_H)
//       = 2 sqrt(5/4) beta sqrt(m* k_H) = sqrt(5) beta sqrt(m* k_H),
// so alpha_common(e) = sqrt(5) beta(e). By the transformation above this is not an
// approximation: it equals hertz_alpha_exact(e) (to the integration accuracy, ~1e-11).
// Defined for e in [0, 1] (alpha_common(0) = sqrt(5), the overdamped threshold).
double hertz_alpha_common(double e);

// Tangential counterpart of the common mapping (Mindlin spring k_t = 8 G* sqrt(R* delta)):
//   gamma_t = 2 sqrt(5/6) beta sqrt(S_t m*),  S_t = k_t,  i.e.  gamma_t = gt sqrt(m* k_t)
// with gt = 2 sqrt(5/6) beta(e) (CoulombTangential::MindlinRestitution).
double mindlin_gt_common(double e);

// Effective moduli of two materials; E = +infinity (rigid) drops its term exactly.
//   1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j
double effective_young(double E_i, double nu_i, double E_j, double nu_j);
//   1/G* = (2 - nu_i)/G_i + (2 - nu_j)/G_j
double effective_shear(double G_i, double nu_i, double G_j, double nu_j);

}  // namespace granular
