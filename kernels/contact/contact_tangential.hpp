// Tangential contact laws. NoTangential: frictionless (no history, no torque).
// CoulombTangential: spring-dashpot kept per contact for the contact's life, rotated into the
// current tangent plane every step, with static/dynamic Coulomb friction (mu = infinity:
// no sliding). The spring stiffness is constant (linear), or grows with the overlap as in
// Mindlin's theory: k_t = kt sqrt(L delta), gamma_t = gt sqrt(L delta), with L = dbar = a_i + a_j
// ("stiffness" form, kt = 2 G_p / (2 - nu)) or L = R ("modulus" form, kt = 8 G*).
// MindlinRestitution: the modulus-form spring k_t = kt sqrt(R delta) (kt = 8 G*) with the
// damping of the restitution mapping, gamma_t = gt sqrt(m* k_t), gt = 2 sqrt(5/6) beta(e)
// (mindlin_gt_common in core/dem/restitution.hpp; pairs with HertzRestitutionNormal).
#pragma once
#include <Kokkos_Core.hpp>

#include "kernels/contact/contact_state.hpp"

namespace granular {

struct NoTangential {
  static constexpr int history = 0;
  static constexpr bool active = false;
};

struct CoulombTangential {
  static constexpr int history = 3;  // spring vector xi
  static constexpr bool active = true;
  enum Law : int {
    Constant = 0,
    MindlinPairDiameter = 1,
    MindlinReducedRadius = 2,
    MindlinRestitution = 3
  };
  struct Params {
    double kt = 0, gt = 0;      // stiffness and viscosity (coefficients for Mindlin laws;
                                // MindlinRestitution: gt is the dimensionless gamma_t/sqrt(m* k_t))
    double mu_s = 0, mu_d = 0;  // static and dynamic friction (may be infinite)
    int law = Constant;
  };
  PairTable<Params> table;

  static CoulombTangential uniform(double kt, double gt, double mu_s, double mu_d,
                                   int law = Constant) {
    return {PairTable<Params>::uniform({kt, gt, mu_s, mu_d, law})};
  }

  // sqrt(L delta) of the Mindlin laws (MindlinRestitution: L = R), 1 for the constant law.
  KOKKOS_INLINE_FUNCTION static double scale(const Params& q, const PairState& s) {
    if (q.law == Constant) return 1.0;
    const double L = q.law == MindlinPairDiameter ? pair_diameter(s) : reduced_radius(s);
    return Kokkos::Experimental::sqrt(L * s.delta);
  }
  // Advances the spring h[0..2] by one step of length dt and returns the force on i.
  // Returns whether the contact slides.
  KOKKOS_INLINE_FUNCTION bool force(const PairState& s, double fn, double dt, double* h,
                                    double f[3]) const {
    const Params& q = table(s.si, s.sj);
    const double c = scale(q, s);
    // The restitution law scales its dashpot with sqrt(m* k_t) instead of sqrt(L delta).
    double k = q.kt * c, g = q.gt * c;
    if (q.law == MindlinRestitution) mindlin_restitution_spring(q.kt, q.gt, c, s.mstar, k, g);
    rotate_into_plane(h, s.n);
    for (int d = 0; d < 3; ++d) h[d] += s.vt[d] * dt;
    // The restitution law's g/k changes with the overlap: its spring keeps no dashpot share
    // after a slip (coulomb_spring).
    return coulomb_spring(h, s.vt, k, g, q.mu_s, q.mu_d, fn, f, q.law != MindlinRestitution);
  }
  // Elastic (spring) part only, from the stored spring, without advancing it (the same
  // spring k_t for every law: damping never enters).
  KOKKOS_INLINE_FUNCTION void elastic_force(const PairState& s, double fn, const double* h,
                                            double f[3]) const {
    const Params& q = table(s.si, s.sj);
    double xi[3] = {h[0], h[1], h[2]};
    rotate_into_plane(xi, s.n);
    const double zero[3] = {0, 0, 0};
    coulomb_spring(xi, zero, q.kt * scale(q, s), 0.0, q.mu_s, q.mu_d, fn, f);
  }
  KOKKOS_INLINE_FUNCTION double energy(const PairState& s, const double* h) const {
    const Params& q = table(s.si, s.sj);
    return 0.5 * q.kt * scale(q, s) * dot3(h, h);
  }
  // The dashpot's largest rate gamma_t / m_t on the tangential mass m_t = (2/7) m of solid
  // spheres (1/m + a^2/I = 7/(2m) per sphere).
  double damping_rate(double m, double delta_ref, double length_max,
                      const PairMask& pairs = PairMask::all()) const {
    const double mt = 2.0 / 7.0 * m;
    return max_over(table, pairs, [&](const Params& q) {
      const double c = q.law == Constant ? 1.0 : std::sqrt(length_max * delta_ref);
      const double g = q.law == MindlinRestitution ? q.gt * std::sqrt(m * q.kt * c) : q.gt * c;
      return g / mt;
    });
  }
  double stiffness(double delta_ref, double length_max,
                   const PairMask& pairs = PairMask::all()) const {
    return max_over(table, pairs, [&](const Params& q) {
      return q.kt * (q.law == Constant ? 1.0 : std::sqrt(length_max * delta_ref));
    });
  }
};

// Rolling and torsion resistance: spring-dashpot-Coulomb on the relative rolling velocity
// v_r = a' (w_i - w_j) x n and torsion velocity v_o = a' ((w_i - w_j).n) n, a' = a_i a_j/(a_i +
// a_j). Torques on i: a' n x f_r and a' f_o; both oppose the relative rotation.
struct NoRolling {
  static constexpr int history = 0;
  static constexpr bool active = false;
};

struct RollingTorsion {
  static constexpr int history = 6;  // rolling spring, torsion spring
  static constexpr bool active = true;
  struct Params {
    double kr = 0, gr = 0, mur = 0;  // rolling
    double ko = 0, go = 0, muo = 0;  // torsion
  };
  PairTable<Params> table;

  static RollingTorsion uniform(const Params& p) { return {PairTable<Params>::uniform(p)}; }

  KOKKOS_INLINE_FUNCTION void torque(const PairState& s, double fn, double dt, double* h,
                                     double q_i[3]) const {
    const Params& q = table(s.si, s.sj);
    const double ar = reduced_radius(s);
    double vr[3], vo[3], fr[3], fo[3], t[3];
    cross3(s.wrel, s.n, vr);
    const double wn = dot3(s.wrel, s.n);
    for (int d = 0; d < 3; ++d) vr[d] *= ar, vo[d] = ar * wn * s.n[d];
    double* sr = h;
    double* so = h + 3;
    rotate_into_plane(sr, s.n);
    // The torsion spring lies along n: keep its signed length on the current normal.
    const double so_len = dot3(so, s.n);
    for (int d = 0; d < 3; ++d) {
      sr[d] += vr[d] * dt;
      so[d] = so_len * s.n[d] + vo[d] * dt;
    }
    coulomb_spring(sr, vr, q.kr, q.gr, q.mur, q.mur, fn, fr);
    coulomb_spring(so, vo, q.ko, q.go, q.muo, q.muo, fn, fo);
    cross3(s.n, fr, t);
    for (int d = 0; d < 3; ++d) q_i[d] += ar * (t[d] + fo[d]);
  }
  KOKKOS_INLINE_FUNCTION double energy(const PairState& s, const double* h) const {
    const Params& q = table(s.si, s.sj);
    return 0.5 * q.kr * dot3(h, h) + 0.5 * q.ko * dot3(h + 3, h + 3);
  }
};

}  // namespace granular
