// Hertz visco-elastic normal contact, in one form that covers both parameterisations of
// the spec:  f = K sqrt(L delta) delta + G sqrt(L delta) d(delta)/dt
//   "stiffness" form:  K = G_p / (1 - nu),  G = alpha_n,  L = dbar = a_i + a_j (pair mean diameter)
//   "modulus" form:    K = (4/3) E*,         G = gamma,    L = R = a_i a_j / (a_i + a_j)
// The modulus form is the classical Hertz force (4/3) E* sqrt(R) delta^{3/2}.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>

#include "kernels/contact/contact_state.hpp"

namespace granular {

struct HertzNormal {
  static constexpr int history = 0;
  struct Params {
    double K = 0.0;               // elastic coefficient
    double G = 0.0;               // viscous coefficient
    bool reduced_radius = false;  // L = R (modulus form) instead of dbar (stiffness form)
  };
  PairTable<Params> table;

  KOKKOS_INLINE_FUNCTION static double length(const Params& q, const PairState& s) {
    return q.reduced_radius ? granular::reduced_radius(s) : pair_diameter(s);
  }
  KOKKOS_INLINE_FUNCTION double force(const PairState& s, double*) const {
    const Params& q = table(s.si, s.sj);
    return hertz_force(q.K, q.G, length(q, s), s.delta, s.delta_dot);
  }
  KOKKOS_INLINE_FUNCTION double elastic_force(const PairState& s, const double*) const {
    const Params& q = table(s.si, s.sj);
    return q.K * Kokkos::Experimental::sqrt(length(q, s) * s.delta) * s.delta;
  }
  // Integral of the elastic force: (2/5) K sqrt(L) delta^{5/2}.
  KOKKOS_INLINE_FUNCTION double energy(const PairState& s, const double*) const {
    const Params& q = table(s.si, s.sj);
    return 0.4 * q.K * Kokkos::Experimental::sqrt(length(q, s) * s.delta) * s.delta * s.delta;
  }

  // Tangent stiffness dF/d(delta) = 1.5 K sqrt(L delta), bounded above with the largest
  // allowed overlap and the largest pair length: the guard assumes the stiffest contact.
  // The dashpot's largest rate G sqrt(L delta) / m, at the largest overlap and length.
  double damping_rate(double m, double delta_ref, double length_max,
                      const PairMask& pairs = PairMask::all()) const {
    double g = 0;
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b)
        if (pairs(a, b)) g = std::max(g, table.p[a][b].G * std::sqrt(length_max * delta_ref));
    return g / m;
  }
  double stiffness(double delta_ref, double length_max,
                   const PairMask& pairs = PairMask::all()) const {
    double k = 0;
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b)
        if (pairs(a, b)) k = std::max(k, 1.5 * table.p[a][b].K * std::sqrt(length_max * delta_ref));
    return k;
  }
  double shortest_duration(double m, double delta_ref, double length_max,
                           const PairMask& pairs = PairMask::all()) const {
    return M_PI * std::sqrt(m / stiffness(delta_ref, length_max, pairs));
  }

  // Modulus form from species moduli: 1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j.
  static Params modulus_form(double E_i, double nu_i, double E_j, double nu_j, double gamma) {
    const double estar = 1.0 / ((1 - nu_i * nu_i) / E_i + (1 - nu_j * nu_j) / E_j);
    return {4.0 / 3.0 * estar, gamma, true};
  }
  // Stiffness form: k_n = (G_p / (1 - nu)) sqrt(dbar delta), gamma_n = alpha_n sqrt(dbar delta).
  static Params stiffness_form(double G_p, double nu, double alpha_n) {
    return {G_p / (1 - nu), alpha_n, false};
  }
};

}  // namespace granular
