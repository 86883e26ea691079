// A contact model = normal law + tangential law + rolling/torsion law, composed at compile
// time so a scene pays only for the physics it switches on: no history storage, no
// rotational degrees of freedom and no extra loads when a part is absent.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>

#include "kernels/contact/contact_hertz.hpp"
#include "kernels/contact/contact_hertz_restitution.hpp"
#include "kernels/contact/contact_hysteretic.hpp"
#include "kernels/contact/contact_linear.hpp"
#include "kernels/contact/contact_state.hpp"
#include "kernels/contact/contact_tangential.hpp"

namespace granular {

struct PairForce {
  double fn = 0;      // normal force (positive: repulsive)
  double f[3] = {};   // total force on i
  double ft[3] = {};  // tangential part of f
  double q[3] = {};   // torque on i
  double qj[3] = {};  // torque on j
};

template <class Normal, class Tangential = NoTangential, class Rolling = NoRolling>
struct ContactModel {
  using normal_type = Normal;
  using tangential_type = Tangential;
  using rolling_type = Rolling;
  static constexpr int normal_offset = 0;
  static constexpr int tangential_offset = Normal::history;
  static constexpr int rolling_offset = Normal::history + Tangential::history;
  static constexpr int history = Normal::history + Tangential::history + Rolling::history;
  // Torques exist only if something tangential acts; otherwise rotations are not integrated.
  static constexpr bool rotations = Tangential::active || Rolling::active;

  Normal normal;
  Tangential tangential;
  Rolling rolling;
  // The normal force of the Coulomb limits (docs/contact_laws.md): false, |f_n| of the total
  // force, elastic plus dashpot, as docs/model_dem.md §3 writes it (the default); true, the
  // elastic part alone. They differ while a damped contact is tensile at its end: over a whole
  // impact the dashpot's impulse vanishes, so with the elastic part gross sliding transfers
  // exactly mu J_n, with the total force mu (J_n + 2 J_tensile).
  bool coulomb_elastic_normal = false;

  // The normal force the Coulomb limits use (the total force fn, or its elastic part).
  KOKKOS_INLINE_FUNCTION double coulomb_normal(const PairState& s, const double* h,
                                               double fn) const {
    return coulomb_elastic_normal ? normal.elastic_force(s, h + normal_offset) : fn;
  }

  // Full evaluation for one step of length dt: advances the history in h.
  KOKKOS_INLINE_FUNCTION void evaluate(const PairState& s, double dt, double* h,
                                       PairForce& out) const {
    out.fn = normal.force(s, h + normal_offset);
    for (int d = 0; d < 3; ++d) out.f[d] = out.fn * s.n[d];
    if constexpr (Tangential::active) {
      tangential.force(s, coulomb_normal(s, h, out.fn), dt, h + tangential_offset, out.ft);
      for (int d = 0; d < 3; ++d) out.f[d] += out.ft[d];
      // The contact point sits mid-overlap: lever arm -(a_i - delta/2) n from i (force ft)
      // and +(a_j - delta/2) n from j (force -ft); the torques then balance exactly.
      const double li = s.ai - 0.5 * s.delta, lj = s.aj - 0.5 * s.delta;
      contact_torques(s.n, out.ft, li, lj, out.q, out.qj);
    }
    if constexpr (Rolling::active) {
      double qr[3] = {0, 0, 0};
      rolling.torque(s, coulomb_normal(s, h, out.fn), dt, h + rolling_offset, qr);
      for (int d = 0; d < 3; ++d) out.q[d] += qr[d], out.qj[d] -= qr[d];
    }
  }

  // Static (elastic) forces of the current state, history untouched: for stress and energy.
  KOKKOS_INLINE_FUNCTION void elastic(const PairState& s, const double* h, PairForce& out) const {
    out.fn = normal.elastic_force(s, h + normal_offset);
    for (int d = 0; d < 3; ++d) out.f[d] = out.fn * s.n[d];
    if constexpr (Tangential::active) {
      tangential.elastic_force(s, out.fn, h + tangential_offset, out.ft);
      for (int d = 0; d < 3; ++d) out.f[d] += out.ft[d];
    }
  }
  KOKKOS_INLINE_FUNCTION double energy(const PairState& s, const double* h) const {
    double e = normal.energy(s, h + normal_offset);
    if constexpr (Tangential::active) e += tangential.energy(s, h + tangential_offset);
    if constexpr (Rolling::active) e += rolling.energy(s, h + rolling_offset);
    return e;
  }

  // Host-side facts for the guards.
  double stiffness(double delta_ref, double length_max,
                   const PairMask& pairs = PairMask::all()) const {
    double k = normal.stiffness(delta_ref, length_max, pairs);
    if constexpr (Tangential::active)
      k = std::max(k, tangential.stiffness(delta_ref, length_max, pairs));
    return k;
  }
  // The shortest half period of the normal and, with friction, of the tangential spring on
  // the tangential mass (2/7) m of solid spheres.
  double shortest_duration(double m, double delta_ref, double length_max,
                           const PairMask& pairs = PairMask::all()) const {
    double t = normal.shortest_duration(m, delta_ref, length_max, pairs);
    if constexpr (Tangential::active) {
      const double kt = tangential.stiffness(delta_ref, length_max, pairs);
      if (kt > 0) t = std::min(t, M_PI * std::sqrt(2.0 / 7.0 * m / kt));
    }
    if constexpr (Rolling::active) {
      // Relative rotation against the rolling or torsion spring: with I = (2/5) m a^2 and the
      // lever a' below either radius, its angular frequency^2 a'^2 k (1/I_i + 1/I_j) stays
      // below (5/2) k / m, so pi sqrt((2/5) m / k) bounds its half period from below.
      const double kr =
          max_over(rolling.table, pairs, [](const auto& q) { return std::max(q.kr, q.ko); });
      if (kr > 0) t = std::min(t, M_PI * std::sqrt(0.4 * m / kr));
    }
    return t;
  }
  // The fastest dashpot rate gamma / m of the contact (normal and tangential).
  double damping_rate(double m, double delta_ref, double length_max,
                      const PairMask& pairs = PairMask::all()) const {
    double r = normal.damping_rate(m, delta_ref, length_max, pairs);
    if constexpr (Tangential::active)
      r = std::max(r, tangential.damping_rate(m, delta_ref, length_max, pairs));
    if constexpr (Rolling::active)  // the same bound: gamma a'^2 / I_eff below (5/2) gamma / m
      r = std::max(r, 2.5 / m * max_over(rolling.table, pairs, [](const auto& q) {
                        return std::max(q.gr, q.go);
                      }));
    return r;
  }
};

using FrictionlessLinear = ContactModel<LinearNormal>;
inline FrictionlessLinear frictionless_linear(double kn, double gn) {
  return {LinearNormal::uniform(kn, gn), {}, {}};
}

}  // namespace granular
