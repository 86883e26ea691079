// Element-test building blocks on a DemSystem: straining the periodic box to a target
// volume fraction, relaxing to static equilibrium, and elastic probing (small isotropic,
// pure-shear and uniaxial strains) that turns stress increments into K, G and M.
// Stresses are positive in compression; strains here are compressive true strains
// eps = -ln(L / L0), so all three moduli come out positive.
#pragma once
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "core/run/error.hpp"
#include "kernels/dem/dem_system.hpp"

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
    // A rate too small for the time step (the strain of a step rounds away) would never end.
    if (!(left < 1e10)) {
      std::ostringstream why;
      why << "reaching the volume fraction " << target << " at the strain rate " << rate
          << " would take " << left << " steps: raise the strain rate";
      throw PhysicsError(why.str());
    }
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
double relax(System& sys, double ratio, long max_steps, bool stop_if_unjammed = false,
             long every = 500) {
  sys.set_strain_rate(0, 0, 0);
  double r = 1e300;
  for (long done = 0; done < max_steps; done += every) {
    sys.step(every);
    const Measurements m = sys.measure();
    sys.check_health(m);
    r = m.epot > 0 ? m.ekin / m.epot : 0.0;
    if (r < ratio) break;
    // Below jamming both energies decay towards zero and their ratio need not fall: once the
    // contact network has come apart, relaxing longer cannot give the configuration a
    // load-bearing network (its moduli are zero).
    if (stop_if_unjammed && !is_jammed(m)) break;
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
  // The isotropic probe's normal part: sum |Delta . n| / sum |(eps l) . n|, and the signed
  // fraction of the affine normal displacement the relaxation undoes (FT: 2 (rho + rho_s)).
  double eta_K_normal = 0, normal_relaxation_K = 0;
  // Fabric change along the probe, relative to the trace F_v of the state before: of the
  // trace in the isotropic and the (first) shear probe, and of F_aa - F_bb in the plane of
  // that shear (compress a, stretch b).
  double fabric_v_change_K = 0, fabric_v_change_G = 0, fabric_dev_change_G = 0;
};

// One probing mode: the state before, the state after straining and relaxing, the true
// strains applied, and the non-affine fluctuation of the contacts at the end.
struct ModeResult {
  Measurements before, after;
  std::array<double, 3> eps{};
  NonAffine na;
};

// Strains the box by sign * amplitude * pattern (compressive true strain per axis) in
// `strain_steps` steps, then relaxes `relax_steps` at fixed box.
template <class System>
void probe_strain(System& sys, const std::array<double, 3>& pattern, double sign, double amplitude,
                  long strain_steps, long relax_steps) {
  const double dt = sys.params().dt;
  double rate[3];
  for (int d = 0; d < 3; ++d)
    rate[d] = std::expm1(-sign * amplitude * pattern[d] / strain_steps) / dt;
  sys.set_strain_rate(rate[0], rate[1], rate[2]);
  sys.step(strain_steps);
  sys.set_strain_rate(0, 0, 0);
  sys.step(relax_steps);
}

template <class System>
ModeResult probe_mode(System& sys, const std::array<double, 3>& pattern, double amplitude,
                      long strain_steps, long relax_steps,
                      const typename System::particles_type::vec_view& drift = {}) {
  ModeResult r;
  const PeriodicBox box0 = sys.box();
  const auto x0 = positions_by_id(sys.particles());
  r.before = sys.measure();
  probe_strain(sys, pattern, +1, amplitude, strain_steps, relax_steps);
  r.after = sys.measure();
  r.na = nonaffine_fluctuation(sys.particles(), sys.neighbor_list(), sys.box(), box0, x0, drift);
  for (int d = 0; d < 3; ++d) r.eps[d] = -std::log(sys.box().len[d] / box0.len[d]);
  return r;
}

// K from the isotropic mode; G from pure-shear modes (compress axis a, stretch axis b) and M
// from uniaxial modes (along axis a), each the mean over the modes given. One shear plane and
// one axis give M = K + 4G/3 only for an isotropic response; the means over the three planes
// and the three axes give it for any linear response (with C the normal-strain block of the
// stiffness: K = sum_ab C_ab / 9, mean M = sum_a C_aa / 3, G_ab = (C_aa + C_bb - C_ab - C_ba)/4).
struct ShearMode {
  const ModeResult* r;
  int a, b;
};
struct UniaxialMode {
  const ModeResult* r;
  int a;
};
inline Moduli moduli_from(const ModeResult& iso, const std::vector<ShearMode>& shear,
                          const std::vector<UniaxialMode>& uni) {
  Moduli out;
  auto p = [](const double* s) { return (s[0] + s[1] + s[2]) / 3.0; };
  const Measurements &a = iso.before, &b = iso.after;
  const double ev = iso.eps[0] + iso.eps[1] + iso.eps[2];
  out.K = (b.pressure - a.pressure) / ev;
  out.K_n = (p(b.stress_normal) - p(a.stress_normal)) / ev;
  out.K_t = (p(b.stress_tangential) - p(a.stress_tangential)) / ev;
  out.eta_K = iso.na.eta_ratio, out.eta_K_per_contact = iso.na.eta;
  out.eta_K_normal = iso.na.eta_normal_ratio, out.normal_relaxation_K = iso.na.normal_relaxation;
  auto fv = [](const Measurements& q) { return q.fabric[0] + q.fabric[1] + q.fabric[2]; };
  if (fv(a) > 0) out.fabric_v_change_K = (fv(b) - fv(a)) / fv(a);
  if (!shear.empty() && fv(shear[0].r->before) > 0) {
    const ShearMode& m = shear[0];
    const Measurements &c = m.r->before, &e = m.r->after;
    out.fabric_v_change_G = (fv(e) - fv(c)) / fv(c);
    out.fabric_dev_change_G =
        ((e.fabric[m.a] - e.fabric[m.b]) - (c.fabric[m.a] - c.fabric[m.b])) / fv(c);
  }
  const double ns = static_cast<double>(shear.size()), nu = static_cast<double>(uni.size());
  for (const ShearMode& m : shear) {
    const Measurements &c = m.r->before, &e = m.r->after;
    auto d = [&m](const double* s) { return s[m.a] - s[m.b]; };
    const double ed = 2 * (m.r->eps[m.a] - m.r->eps[m.b]);
    out.G += (d(e.stress) - d(c.stress)) / ed / ns;
    out.G_n += (d(e.stress_normal) - d(c.stress_normal)) / ed / ns;
    out.G_t += (d(e.stress_tangential) - d(c.stress_tangential)) / ed / ns;
    out.eta_G += m.r->na.eta_ratio / ns;
  }
  for (const UniaxialMode& m : uni) {
    out.M += (m.r->after.stress[m.a] - m.r->before.stress[m.a]) / m.r->eps[m.a] / nu;
    out.eta_M += m.r->na.eta_ratio / nu;
  }
  return out;
}

// G from pure shear compressing x and stretching y, M from uniaxial x.
inline Moduli moduli_from(const ModeResult& iso, const ModeResult& shear, const ModeResult& uni) {
  return moduli_from(iso, std::vector<ShearMode>{{&shear, 0, 1}},
                     std::vector<UniaxialMode>{{&uni, 0}});
}

const std::array<double, 3> kIsotropic = {1, 1, 1}, kPureShear = {1, -1, 0}, kUniaxial = {1, 0, 0};

// Reversibility of a pre-strain: from a state relaxed to E_kin/E_pot < relax_ratio, strain
// by `prestrain` along `pattern` (kIsotropic or kPureShear) and relax; reverse by `amplitude`
// (the unloading modulus), then by the rest of the pre-strain (the stress left behind). The
// moduli are in the mode's own measure: K = dp / (volumetric strain) for the isotropic mode,
// G = d(s_xx - s_yy) / (2 (e_x - e_y)) for pure shear.
struct Reversibility {
  double loading = 0;        // secant modulus over the pre-strain
  double unloading = 0;      // modulus over the first `amplitude` of the reversal
  double residual = 0;       // stress left after the whole reversal / stress the pre-strain added
  double relaxed_ratio = 0;  // E_kin/E_pot reached before the pre-strain
};

template <class System>
Reversibility probe_reversibility(System& sys, const std::array<double, 3>& pattern,
                                  double prestrain, double amplitude, long prestrain_steps,
                                  long amplitude_steps, long relax_steps, double relax_ratio,
                                  long relax_max) {
  const bool iso = pattern == kIsotropic;
  auto stress = [iso](const Measurements& m) {
    return iso ? m.pressure : m.stress[0] - m.stress[1];
  };
  auto strain = [iso](const PeriodicBox& from, const PeriodicBox& to) {
    double e[3];
    for (int d = 0; d < 3; ++d) e[d] = -std::log(to.len[d] / from.len[d]);
    return iso ? e[0] + e[1] + e[2] : 2 * (e[0] - e[1]);
  };
  Reversibility r;
  r.relaxed_ratio = relax(sys, relax_ratio, relax_max);
  const PeriodicBox box0 = sys.box();
  const Measurements m0 = sys.measure();
  probe_strain(sys, pattern, +1, prestrain, prestrain_steps, relax_steps);
  const PeriodicBox box1 = sys.box();
  const Measurements m1 = sys.measure();
  probe_strain(sys, pattern, -1, amplitude, amplitude_steps, relax_steps);
  const Measurements m2 = sys.measure();
  r.loading = (stress(m1) - stress(m0)) / strain(box0, box1);
  r.unloading = (stress(m2) - stress(m1)) / strain(box1, sys.box());
  probe_strain(sys, pattern, -1, prestrain - amplitude, prestrain_steps, relax_steps);
  r.residual = (stress(sys.measure()) - stress(m0)) / (stress(m1) - stress(m0));
  return r;
}

// Probes a relaxed system in place, keeping its contact history: for each mode (isotropic,
// pure shear compressing x and stretching y, uniaxial along x) strain by `amplitude`
// (compressive true strain) in `strain_steps` steps, relax `relax_steps` at fixed box,
// measure, then reverse the strain the same way (the reversal test) and relax again.
template <class System>
Moduli probe_moduli(System& sys, double amplitude, long strain_steps, long relax_steps,
                    double* reversal_residual = nullptr) {
  ModeResult r[3];
  const std::array<double, 3> modes[3] = {kIsotropic, kPureShear, kUniaxial};
  for (int m = 0; m < 3; ++m) {
    r[m] = probe_mode(sys, modes[m], amplitude, strain_steps, relax_steps);
    probe_strain(sys, modes[m], -1, amplitude, strain_steps, relax_steps);
    if (m == 0 && reversal_residual)
      *reversal_residual = (sys.measure().pressure - r[0].before.pressure) /
                           (r[0].after.pressure - r[0].before.pressure);
  }
  return moduli_from(r[0], r[1], r[2]);
}

// Probes a state that `make()` restores afresh for every mode (a saved configuration), so
// the modes do not disturb one another. A reference run from the same state without
// strain, as long as a probe, gives the stress the state would reach on its own (residual
// relaxation): stress increments are taken against it, which removes that drift from the
// moduli; the particle displacements of that run are likewise subtracted before the
// non-affine fluctuation is computed. The isotropic probe is then reversed for the
// reversal test.
//
// orientations = 3 probes pure shear in the three planes (xy, yz, zx) and uniaxial strain
// along the three axes and reports the means (see moduli_from); 1 probes xy and x only.
//
// The reference run depends only on the state, the model and its length, so probes of one
// state and model may share it through `references` (an amplitude sweep whose step count
// reaches its cap runs every larger amplitude for the same length): the moduli are bitwise
// those of a probe that runs its own.
template <class System>
struct ReferenceRuns {
  struct Run {
    int durations = 0;      // probe durations run: 0 (none yet), 1, or 2 (for the reversal)
    Measurements one, two;  // after one and after two probe durations
    typename System::particles_type::vec_view drift;  // displacements over the first
  };
  std::map<long, Run> by_length;  // keyed by strain_steps + relax_steps
};

template <class Factory, class System = std::decay_t<std::invoke_result_t<const Factory&>>>
Moduli probe_moduli_restarting(const Factory& make, double amplitude, long strain_steps,
                               long relax_steps, double* reversal_residual = nullptr,
                               int orientations = 1, ReferenceRuns<System>* references = nullptr) {
  std::vector<std::array<double, 3>> modes = {kIsotropic, kPureShear, kUniaxial};
  if (orientations == 3) modes.insert(modes.end(), {{0, 1, -1}, {-1, 0, 1}, {0, 1, 0}, {0, 0, 1}});
  std::vector<ModeResult> r(modes.size());
  const long length = strain_steps + relax_steps;
  typename ReferenceRuns<System>::Run own;
  auto& ref = references ? references->by_length[length] : own;
  const int needed = reversal_residual ? 2 : 1;
  if (ref.durations < needed) {
    auto sys = make();
    const auto x0 = positions_by_id(sys.particles());
    sys.step(length);
    ref.one = sys.measure();
    ref.drift = displacement_by_id<typename System::execution_space>(
        x0, positions_by_id(sys.particles()), sys.box());
    if (needed == 2) {
      sys.step(length);
      ref.two = sys.measure();
    }
    ref.durations = needed;
  }
  const Measurements &reference = ref.one, &reference2 = ref.two;
  const auto& drift = ref.drift;
  for (size_t m = 0; m < modes.size(); ++m) {
    auto sys = make();
    r[m] = probe_mode(sys, modes[m], amplitude, strain_steps, relax_steps, drift);
    r[m].before = reference;
    if (m == 0 && reversal_residual) {
      probe_strain(sys, modes[m], -1, amplitude, strain_steps, relax_steps);
      *reversal_residual = (sys.measure().pressure - reference2.pressure) /
                           (r[0].after.pressure - reference.pressure);
    }
  }
  if (orientations != 3) return moduli_from(r[0], r[1], r[2]);
  // Modes 1, 3, 4: compress x / y / z and stretch y / z / x; modes 2, 5, 6: along x, y, z.
  // Typed lists: a bare braced list could also initialise a ModeResult, which nvcc's front end
  // reports as an ambiguous call.
  return moduli_from(r[0], std::vector<ShearMode>{{&r[1], 0, 1}, {&r[3], 1, 2}, {&r[4], 2, 0}},
                     std::vector<UniaxialMode>{{&r[2], 0}, {&r[5], 1}, {&r[6], 2}});
}

}  // namespace granular
