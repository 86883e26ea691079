// Isotropic pressure servo for Hertzian packings in a periodic box: configurations picked at
// target pressures instead of target volume fractions.
//
// Hertz contacts give two estimates from one measurement, without probing: with
// E_pot = sum (2/5) f delta and P V = (1/3) sum f l (l ~ pair diameter d), the volumetric
// strain of an affine deformation from the contact-free state is eps = 3 <delta>_f / d
// = 5 E_pot / (2 P V), and P grows as eps^{3/2}, so the strain that takes P to the target
// is eps ((P_t / P)^{2/3} - 1), and the affine bulk modulus is K = (3/2) P / eps
// = (3/5) P^2 V / E_pot. The servo strains the box isotropically and continuously at a rate
// proportional to that pressure error (the strain to the target spread over
// `response_crossings` crossing times, bounded by `max_step` per crossing time), re-chosen
// every `check_crossings`; it ends when P is within the tolerance and E_kin/E_pot is small.
// A continuous servo follows the creep of a frictional packing near jamming, which keeps
// collapsing under a held box (a ramp-and-hold servo chased it for dozens of cycles). Times
// are crossing times of a compression wave through the box, L sqrt(rho / K), so glass and
// rubber packings are strained equally quasi-statically; the affine K overestimates the
// packing's (non-affine relaxation), which only makes the servo gentler.
#pragma once
#include <algorithm>
#include <cmath>

#include "kernels/dem/dem_system.hpp"

namespace granular {

struct ServoSettings {
  double tolerance = 0.02;          // |P / P_target - 1| at the end
  double ekin_ratio = 1e-6;         // E_kin / E_pot at the end
  double response_crossings = 2.0;  // the strain to the target is applied over this time
  double max_step = 0.002;          // largest volumetric strain per crossing time
  double check_crossings = 0.25;    // the rate is re-chosen this often
  // Integral action: the proportional rate accumulated over this many crossing times is added
  // to it (0: proportional alone). A frictional packing near jamming consolidates under the
  // servo's strain; a proportional servo chasing that creep keeps a steady offset behind it
  // (docs/guide_waves.md, "Why glass at 0.1 MPa does not converge"), which the accumulated
  // rate removes.
  double integral_crossings = 0.0;
  long min_phase_steps = 20, max_phase_steps = 50000;
  int max_cycles = 2000;  // checks before giving up
};

struct ServoResult {
  bool converged = false;
  int cycles = 0;
  long steps = 0;
  Measurements m;
  double ekin_ratio = 0;
};

// Affine Hertz estimates from one measurement (see above); 0 without contacts.
inline double hertz_affine_strain(const Measurements& m) {
  return m.pressure > 0 && m.epot > 0 ? 2.5 * m.epot / (m.pressure * m.volume) : 0.0;
}
inline double hertz_affine_bulk_modulus(const Measurements& m) {
  return m.epot > 0 ? 0.6 * m.pressure * m.pressure * m.volume / m.epot : 0.0;
}

// Time a compression wave of modulus ~K takes to cross the box (its longest edge) in a
// packing of bulk density rho: the time scale of quasi-static straining and relaxation.
// Infinite without a contact network.
inline double crossing_time(const Measurements& m, double rho, double length) {
  const double K = hertz_affine_bulk_modulus(m);
  return K > 0 ? length * std::sqrt(rho / K) : INFINITY;
}

// Steps of `crossings` crossing times, within the settings' bounds.
inline long phase_steps(double crossings, double tc, double dt, const ServoSettings& s) {
  const double n = std::isfinite(tc) ? std::ceil(crossings * tc / dt) : 1e300;
  return std::clamp(static_cast<long>(std::min(n, 1e15)), s.min_phase_steps, s.max_phase_steps);
}

// Applies a compressive volumetric true strain `eps_v` (negative: expansion) isotropically
// in `steps` steps, then stops the box.
template <class System>
void strain_volume(System& sys, double eps_v, long steps) {
  const double rate = std::expm1(-eps_v / 3.0 / static_cast<double>(steps)) / sys.params().dt;
  sys.set_strain_rate(rate, rate, rate);
  sys.step(steps);
  sys.set_strain_rate(0, 0, 0);
}

// Compresses at the constant volumetric rate `rate` (per time unit) until the pressure
// reaches `pressure`, measuring every `every` steps; gives up at phi_max. Returns the steps.
template <class System>
long compress_to_pressure(System& sys, double pressure, double rate, long every, double phi_max) {
  const double r = std::expm1(-rate / 3.0 * sys.params().dt) / sys.params().dt;
  sys.set_strain_rate(r, r, r);
  long steps = 0;
  while (true) {
    sys.step(every);
    steps += every;
    const Measurements m = sys.measure();
    sys.check_health(m);
    if (m.pressure >= pressure || m.phi >= phi_max) break;
  }
  sys.set_strain_rate(0, 0, 0);
  return steps;
}

// Drives the packing to `target` pressure (see the header comment). `rho` is the bulk
// density (mass / box volume) for the crossing time.
template <class System>
ServoResult servo_to_pressure(System& sys, double target, double rho, const ServoSettings& s) {
  ServoResult out;
  const double dt = sys.params().dt;
  const PeriodicBox& box = sys.box();
  const double goal = std::pow(target, 2.0 / 3.0);
  double tc_last = INFINITY;
  double integral = 0;  // the integral action's rate (volumetric, compressive positive)
  while (true) {
    const Measurements m = sys.measure();
    sys.check_health(m);
    out.m = m;
    out.ekin_ratio = m.epot > 0 ? m.ekin / m.epot : INFINITY;
    const double err = m.pressure / target - 1;
    if (std::fabs(err) < s.tolerance && out.ekin_ratio < s.ekin_ratio) {
      out.converged = true;
      break;
    }
    if (out.cycles >= s.max_cycles) break;
    // Without a contact network there is no crossing time yet: keep the last one.
    const double tc_now = crossing_time(m, rho, std::max({box.len[0], box.len[1], box.len[2]}));
    if (std::isfinite(tc_now)) tc_last = tc_now;
    const double tc = std::isfinite(tc_last) ? tc_last : s.max_phase_steps * dt;
    // Strain to the target by the affine Hertz law, applied over `response` crossing times.
    const double q = m.pressure > 0 ? std::pow(m.pressure, 2.0 / 3.0) : 0.0;
    const double eps = hertz_affine_strain(m);
    const double needed = eps > 0 ? (goal - q) * eps / q : s.max_step;
    const double bound = s.max_step / tc;
    const double proportional = needed / (s.response_crossings * tc);
    const long n = phase_steps(s.check_crossings, tc, dt, s);
    if (s.integral_crossings > 0)  // bounded like the rate itself, so it cannot wind up
      integral = std::clamp(integral + proportional * (n * dt) / (s.integral_crossings * tc),
                            -bound, bound);
    const double rate = std::clamp(
        s.integral_crossings > 0 ? proportional + integral : proportional, -bound, bound);
    const double r = std::expm1(-rate / 3.0 * dt) / dt;
    sys.set_strain_rate(r, r, r);
    sys.step(n);
    out.steps += n;
    ++out.cycles;
  }
  sys.set_strain_rate(0, 0, 0);
  return out;
}

}  // namespace granular
