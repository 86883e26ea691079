// Hertz normal contact with damping set by a coefficient of restitution (docs/model_dem.md §10):
//     f = k_H delta^{3/2} + eta delta^{1/4} d(delta)/dt,
//     k_H = K sqrt(R*), K = (4/3) E*,  eta = alpha sqrt(m* k_H),
// with R* the reduced radius (a_i for a wall) and m* the reduced mass (m_i for a wall).
// The collision then rebounds with a restitution that depends on alpha alone, not on the
// impact speed or the materials: alpha = hertz_alpha_exact(e) (core/dem/restitution.hpp), which
// equals the common DEM mapping hertz_alpha_common(e) = sqrt(5) beta(e).
// In one evaluation: with r = sqrt(R* delta),  k_H delta^{3/2} = K r delta and
// eta delta^{1/4} = alpha sqrt(m* K r), so two square roots per contact.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>

#include "core/dem/restitution.hpp"
#include "kernels/contact/contact_state.hpp"

namespace granular {

struct HertzRestitutionNormal {
  static constexpr int history = 0;
  struct Params {
    double K = 0.0;      // (4/3) E*
    double alpha = 0.0;  // dimensionless damping, alpha(e); 0 is elastic
  };
  PairTable<Params> table;

  static HertzRestitutionNormal uniform(double K, double alpha) {
    return {PairTable<Params>::uniform({K, alpha})};
  }
  // From the effective modulus E* (effective_young) and the damping alpha(e).
  static Params modulus_form(double estar, double alpha) { return {4.0 / 3.0 * estar, alpha}; }
  // From E* and the coefficient of restitution e in (0, 1] (host only, about 7 ms).
  static Params from_restitution(double estar, double e) {
    return modulus_form(estar, hertz_alpha_exact(e));
  }

  KOKKOS_INLINE_FUNCTION double force(const PairState& s, double*) const {
    const Params& q = table(s.si, s.sj);
    double r;
    return hertz_restitution_force(q.K, q.alpha, reduced_radius(s), s.mstar, s.delta, s.delta_dot,
                                   r);
  }
  KOKKOS_INLINE_FUNCTION double elastic_force(const PairState& s, const double*) const {
    const Params& q = table(s.si, s.sj);
    return q.K * Kokkos::Experimental::sqrt(reduced_radius(s) * s.delta) * s.delta;
  }
  // Integral of the elastic force: (2/5) K sqrt(R*) delta^{5/2}.
  KOKKOS_INLINE_FUNCTION double energy(const PairState& s, const double*) const {
    const Params& q = table(s.si, s.sj);
    return 0.4 * q.K * Kokkos::Experimental::sqrt(reduced_radius(s) * s.delta) * s.delta * s.delta;
  }

  // Tangent stiffness dF/d(delta) = 1.5 K sqrt(R* delta), bounded above with the largest
  // allowed overlap and the largest pair length (R* < length_max): the guard assumes the
  // stiffest contact.
  // The dashpot's rate alpha sqrt(m k_H)/m = alpha sqrt(k_H/m): below the period's scale for
  // any alpha <= sqrt 5, listed for the guard's completeness.
  double damping_rate(double m, double delta_ref, double length_max,
                      const PairMask& pairs = PairMask::all()) const {
    double r = 0;
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b) {
        if (!pairs(a, b)) continue;
        const double k = table.p[a][b].K * std::sqrt(length_max * delta_ref);
        r = std::max(r, table.p[a][b].alpha * std::sqrt(k / m));
      }
    return r;
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
};

}  // namespace granular
