// Linear visco-elastic normal contact: f = k_n delta + gamma_n d(delta)/dt.
// The force is allowed to become slightly tensile at the end of a damped collision: this
// is the model whose closed forms (t_c = pi/omega, e = exp(-eta t_c)) the spec states.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>

#include "kernels/contact/contact_state.hpp"

namespace granular {

struct LinearNormal {
  static constexpr int history = 0;
  struct Params {
    double kn = 0.0;  // normal stiffness
    double gn = 0.0;  // normal viscosity
  };
  PairTable<Params> table;

  static LinearNormal uniform(double kn, double gn) {
    return {PairTable<Params>::uniform({kn, gn})};
  }

  KOKKOS_INLINE_FUNCTION double force(const PairState& s, double*) const {
    const Params& q = table(s.si, s.sj);
    return linear_normal_force(q.kn, q.gn, s.delta, s.delta_dot);
  }
  KOKKOS_INLINE_FUNCTION double elastic_force(const PairState& s, const double*) const {
    return table(s.si, s.sj).kn * s.delta;
  }
  KOKKOS_INLINE_FUNCTION double energy(const PairState& s, const double*) const {
    return 0.5 * table(s.si, s.sj).kn * s.delta * s.delta;
  }

  // Closed forms for a pair of species (0, 0) and reduced mass m (docs/model_dem.md §2.1).
  double omega(double m, int si = 0, int sj = 0) const {
    const Params& q = table.p[si][sj];
    const double eta = q.gn / (2.0 * m);
    return std::sqrt(q.kn / m - eta * eta);
  }
  double contact_duration(double m, int si = 0, int sj = 0) const {
    return M_PI / omega(m, si, sj);
  }
  double restitution(double m, int si = 0, int sj = 0) const {
    return std::exp(-table.p[si][sj].gn / (2.0 * m) * contact_duration(m, si, sj));
  }
  // Shortest collision for the time-step guard over all pairs; overdamped pairs fall
  // back to the undamped half period, which is shorter.
  double shortest_duration(double m, double /*delta_ref*/ = 0, double /*length_max*/ = 0,
                           const PairMask& pairs = PairMask::all()) const {
    double t = 1e300;
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b) {
        const Params& q = table.p[a][b];
        if (!pairs(a, b) || !(q.kn > 0)) continue;
        const double eta = q.gn / (2.0 * m);
        t = std::min(t, q.kn / m > eta * eta ? M_PI / std::sqrt(q.kn / m - eta * eta)
                                             : M_PI * std::sqrt(m / q.kn));
      }
    return t;
  }
  // The dashpot's largest rate gamma / m on mass m (an explicit step needs it below 1/dt).
  double damping_rate(double m, double = 0, double = 0,
                      const PairMask& pairs = PairMask::all()) const {
    return max_over(table, pairs, [](const Params& q) { return q.gn; }) / m;
  }
  double stiffness(double /*delta_ref*/ = 0, double /*length_max*/ = 0,
                   const PairMask& pairs = PairMask::all()) const {
    return max_over(table, pairs, [](const Params& q) { return q.kn; });
  }
};

}  // namespace granular
