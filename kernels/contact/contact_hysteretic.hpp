// Hysteretic, adhesive, elasto-plastic normal contact (piecewise linear): loading on k1,
// un/reloading on k2 from the plastic overlap delta0 = (1 - k1/k2) delta_max, adhesion
// limited by the branch -kc delta; plus a normal dashpot gamma_n d(delta)/dt.
// History per contact: delta_max. When unloading reaches the adhesive branch, delta_max is
// lowered so that reloading leaves that branch along a k2 line through the current point.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>

#include "kernels/contact/contact_state.hpp"

namespace granular {

struct HystereticNormal {
  static constexpr int history = 1;  // delta_max
  struct Params {
    double k1 = 0, k2 = 0, kc = 0, gn = 0;
  };
  PairTable<Params> table;

  // Elastic-plastic part (hysteretic_elastic_force of kernels/contact/lane_law.inc, the one
  // source the host's four-lane paths share). Moves the history dmax (delta_max) as the
  // contact loads further or slides along the adhesive branch; callers that only look pass a
  // copy.
  KOKKOS_INLINE_FUNCTION static double piecewise(const Params& q, double delta, double& dmax) {
    return hysteretic_elastic_force(q.k1, q.k2, q.kc, delta, dmax);
  }
  KOKKOS_INLINE_FUNCTION double force(const PairState& s, double* h) const {
    const Params& q = table(s.si, s.sj);
    return piecewise(q, s.delta, h[0]) + q.gn * s.delta_dot;
  }
  KOKKOS_INLINE_FUNCTION double elastic_force(const PairState& s, const double* h) const {
    double dmax = h[0];
    return piecewise(table(s.si, s.sj), s.delta, dmax);
  }
  // Energy recoverable along the current k2 branch (what unloading to zero force returns),
  // or on the loading/adhesive branches the elastic energy of the equivalent k2 spring.
  KOKKOS_INLINE_FUNCTION double energy(const PairState& s, const double* h) const {
    const Params& q = table(s.si, s.sj);
    const double f = elastic_force(s, h);
    return 0.5 * f * f / q.k2;
  }

  double damping_rate(double m, double = 0, double = 0,
                      const PairMask& pairs = PairMask::all()) const {
    return max_over(table, pairs, [](const Params& q) { return q.gn; }) / m;
  }
  double stiffness(double = 0, double = 0, const PairMask& pairs = PairMask::all()) const {
    return max_over(table, pairs, [](const Params& q) { return std::max(q.k2, q.kc); });
  }
  double shortest_duration(double m, double = 0, double = 0,
                           const PairMask& pairs = PairMask::all()) const {
    return M_PI * std::sqrt(m / stiffness(0, 0, pairs));
  }
  static HystereticNormal uniform(double k1, double k2, double kc, double gn) {
    return {PairTable<Params>::uniform({k1, k2, kc, gn})};
  }
};

}  // namespace granular
