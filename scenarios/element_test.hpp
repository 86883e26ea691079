// Element-test building blocks on a DemSystem: straining the periodic box to a target
// volume fraction, relaxing to static equilibrium, and elastic probing (small isotropic,
// pure-shear and uniaxial strains) that turns stress increments into K, G and M.
// Stresses are positive in compression; strains here are compressive true strains
// eps = -ln(L / L0), so all three moduli come out positive.
#pragma once
#include <array>
#include <cmath>
#include <functional>

#include "kernels/dem_system.hpp"

namespace granular {

// Strains the box isotropically at `rate` (per axis, signed) until phi crosses `target`;
// calls `sample` every `every` steps. Returns the steps taken.
// With `rate_of`, the rate is re-chosen from each sample (e.g. for a target inertial
// number); it must keep the sign of `rate`.
template <class System>
long strain_to_phi(System& sys, double target, double rate, long every,
                   const std::function<void(const Measurements&)>& sample,
                   const std::function<double(const Measurements&)>& rate_of = nullptr) {
  if (rate_of) rate = rate_of(sys.measure());
  sys.set_strain_rate(rate, rate, rate);
  long steps = 0;
  const bool compress = rate < 0;
  while (true) {
    const double phi = sys.particle_volume() / sys.box().volume();
    if (compress ? phi >= target : phi <= target) break;
    // Steps left to the target at this rate, capped by the sampling interval.
    const double left = std::log(phi / target) / (3.0 * std::log1p(rate * sys.params().dt));
    const long n = std::max(1L, std::min(every, static_cast<long>(std::ceil(left))));
    sys.step(n);
    steps += n;
    const Measurements m = sys.measure();
    sys.check_health(m);
    if (sample) sample(m);
    if (rate_of) {
      rate = rate_of(m);
      sys.set_strain_rate(rate, rate, rate);
    }
  }
  sys.set_strain_rate(0, 0, 0);
  return steps;
}

// Constant-volume relaxation until E_kin/E_pot < ratio (or max_steps). Returns the ratio.
template <class System>
double relax(System& sys, double ratio, long max_steps, long every = 500) {
  sys.set_strain_rate(0, 0, 0);
  double r = 1e300;
  for (long done = 0; done < max_steps; done += every) {
    sys.step(every);
    const Measurements m = sys.measure();
    sys.check_health(m);
    r = m.epot > 0 ? m.ekin / m.epot : 0.0;
    if (r < ratio) break;
  }
  return r;
}

struct Moduli {
  double K = 0, G = 0, M = 0;                 // bulk, shear, P-wave (uniaxial) moduli
  double K_n = 0, K_t = 0, G_n = 0, G_t = 0;  // from normal / tangential contact forces
  // Non-affine displacement fluctuation at the end of each loading probe, as
  // sum_c |Delta| / sum_c |eps l| (defined for every mode), and for the isotropic probe also
  // the per-contact mean (1/M) sum_c |Delta| / |eps l| (there eps l never vanishes).
  double eta_K = 0, eta_G = 0, eta_M = 0, eta_K_per_contact = 0;
};

// Probes a relaxed system in place, keeping its contact history: for each mode (isotropic,
// pure shear compressing x and stretching y, uniaxial along x) strain by `amplitude`
// (compressive true strain) in `strain_steps` steps, relax `relax_steps` at fixed box,
// measure, then reverse the strain the same way (the reversal test) and relax again.
template <class System>
Moduli probe_moduli(System& sys, double amplitude, long strain_steps, long relax_steps,
                    double* reversal_residual = nullptr) {
  const double dt = sys.params().dt;
  auto strain = [&](const std::array<double, 3>& pattern, double sign) {
    double rate[3];
    for (int d = 0; d < 3; ++d)
      rate[d] = std::expm1(-sign * amplitude * pattern[d] / strain_steps) / dt;
    sys.set_strain_rate(rate[0], rate[1], rate[2]);
    sys.step(strain_steps);
    sys.set_strain_rate(0, 0, 0);
    sys.step(relax_steps);
  };
  NonAffine na;
  auto run = [&](const std::array<double, 3>& pattern, Measurements& before, Measurements& after,
                 std::array<double, 3>& eps) {
    const PeriodicBox box0 = sys.box();
    const auto x0 = positions_by_id(sys.particles());
    before = sys.measure();
    strain(pattern, +1);
    after = sys.measure();
    na = nonaffine_fluctuation(sys.particles(), sys.neighbor_list(), sys.box(), box0, x0);
    for (int d = 0; d < 3; ++d) eps[d] = -std::log(sys.box().len[d] / box0.len[d]);
    strain(pattern, -1);
  };
  Moduli out;
  Measurements a, b;
  std::array<double, 3> e;
  auto p = [](const double* s) { return (s[0] + s[1] + s[2]) / 3.0; };
  run({1, 1, 1}, a, b, e);
  const double ev = e[0] + e[1] + e[2];
  out.K = (b.pressure - a.pressure) / ev;
  out.K_n = (p(b.stress_normal) - p(a.stress_normal)) / ev;
  out.K_t = (p(b.stress_tangential) - p(a.stress_tangential)) / ev;
  out.eta_K = na.eta_ratio, out.eta_K_per_contact = na.eta;
  if (reversal_residual)
    *reversal_residual = (sys.measure().pressure - a.pressure) / (b.pressure - a.pressure);
  run({1, -1, 0}, a, b, e);
  const double ed = 2 * (e[0] - e[1]);
  out.G = ((b.stress[0] - b.stress[1]) - (a.stress[0] - a.stress[1])) / ed;
  out.G_n =
      ((b.stress_normal[0] - b.stress_normal[1]) - (a.stress_normal[0] - a.stress_normal[1])) / ed;
  out.G_t = ((b.stress_tangential[0] - b.stress_tangential[1]) -
             (a.stress_tangential[0] - a.stress_tangential[1])) /
            ed;
  out.eta_G = na.eta_ratio;
  run({1, 0, 0}, a, b, e);
  out.M = (b.stress[0] - a.stress[0]) / e[0];
  out.eta_M = na.eta_ratio;
  return out;
}

}  // namespace granular
