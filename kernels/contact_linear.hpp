// Linear visco-elastic normal contact: f = k_n delta + gamma_n d(delta)/dt.
// The force is allowed to become slightly tensile at the end of a damped collision: this
// is the model whose closed forms (t_c = pi/omega, e = exp(-eta t_c)) the spec states.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>

namespace granular {

struct LinearNormal {
  double kn = 0.0;  // normal stiffness
  double gn = 0.0;  // normal viscosity

  KOKKOS_INLINE_FUNCTION double force(double delta, double delta_dot) const {
    return kn * delta + gn * delta_dot;
  }
  KOKKOS_INLINE_FUNCTION double energy(double delta) const { return 0.5 * kn * delta * delta; }

  // Closed forms for a pair of reduced mass m (dem.md section 2).
  double omega(double m) const {
    const double eta = gn / (2.0 * m);
    return std::sqrt(kn / m - eta * eta);
  }
  double contact_duration(double m) const { return M_PI / omega(m); }
  double restitution(double m) const {
    return std::exp(-gn / (2.0 * m) * contact_duration(m));
  }
  // Shortest collision for the time-step guard; overdamped pairs fall back to the
  // undamped half period, which is shorter.
  double shortest_duration(double m) const {
    const double eta = gn / (2.0 * m);
    return kn / m > eta * eta ? contact_duration(m) : M_PI * std::sqrt(m / kn);
  }
  double stiffness() const { return kn; }
};

}  // namespace granular
