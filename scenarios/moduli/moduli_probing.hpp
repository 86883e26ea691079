// Probing one configuration of the elastic_moduli study: the probing model (friction and
// tangential stiffness of the preparation or of the scene), K, G, M with their partitions
// and non-affine fluctuation, the theories at the same phi Z, the rate/amplitude halving
// check and amplitude sweeps; each configuration's rows and sweeps are returned as data
// (ConfigResults) for the study to add to its outputs.
#pragma once
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <string>
#include <type_traits>

#include "kernels/contact/contact_hysteretic.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/element_test.hpp"
#include "scenarios/moduli/moduli_outputs.hpp"
#include "scenarios/moduli/moduli_setup.hpp"
#include "scenarios/moduli/moduli_theory.hpp"

namespace granular::moduli_study {

using Outputs = ModuliOutputs;

// The same contact model with another friction coefficient (infinity: no sliding).
template <class Model>
Model with_friction(Model m, double mu) {
  if constexpr (Model::tangential_type::active) {
    for (auto& row : m.tangential.table.p)
      for (auto& q : row) q.mu_s = q.mu_d = mu;
  }
  return m;
}

// The same contact model with another adhesive stiffness k_c (hysteretic normal law only).
template <class Model>
Model with_cohesion(Model m, double kc) {
  if constexpr (std::is_same_v<typename Model::normal_type, HystereticNormal>) {
    for (auto& row : m.normal.table.p)
      for (auto& q : row) q.kc = kc;
  }
  return m;
}

// The same contact model with another (constant) tangential spring stiffness.
template <class Model>
Model with_tangential_stiffness(Model m, double kt) {
  if constexpr (Model::tangential_type::active) {
    for (auto& row : m.tangential.table.p)
      for (auto& q : row) q.kt = kt;
  }
  return m;
}

// Mean diameter, density and size moment D = <d^2>/<d^3> dbar of a configuration.
struct SizeStats {
  double dbar = 0, density = 0, D = 0;
};
SizeStats size_stats(const ConfigState& c);

// Mean normal tangent stiffness dF/d(delta) over the contacts of a configuration (the k_n
// of the dimensionless moduli): k_n (linear), k2 (hysteretic, the un/reloading branch),
// 1.5 K sqrt(L delta) (Hertz). Host code, all pairs: it runs once per configuration.
double mean_normal_stiffness(const ConfigState& c, const ContactConfig& cc);

// Tangential over normal tangent stiffness of the probing model, for the theories.
double stiffness_ratio(const ContactConfig& cc, double kn_mean, double kt_override);

// Strain steps that give an axial probing rate I sqrt(P / rho) / dbar (inertial number I).
long steps_for(const Setup& s, double amplitude, double base_rate);

double rel_change(double a, double b);  // |a / b - 1|

// Probes a saved configuration: each mode restarts from it, so probes do not disturb one
// another and give bitwise the same result whether the state is in memory or read back.
template <class Model>
Moduli probe_config(const ConfigState& c, const Model& model, const Setup& s, double amplitude,
                    long steps, double* reversal,
                    ReferenceRuns<DemSystem<Exec, Model>>* references = nullptr) {
  auto make = [&] { return restart_system<DemSystem<Exec, Model>>(c, model, s.params); };
  return probe_moduli_restarting(make, amplitude, steps, s.probe_relax, reversal, s.orientations,
                                 references);
}

// What the probes of one configuration share: its size statistics and mean normal stiffness,
// the scale k_n / dbar of its dimensionless moduli, its measurements, and the probing rate
// and step count its pressure gives.
struct ProbeBasis {
  SizeStats st;
  double kn = 0, scale = 0;
  Measurements m;
  double inertia_scale = 0, base_rate = 0, probe_I = 0;
  long steps = 0;
  // Below jamming the moduli vanish: probing such a state only measures the drift of a
  // dissolving network (at the inertial-number rate of its tiny pressure, minutes per mode),
  // so it is left out and its moduli are reported as zero.
  bool jammed = false;
};
// From the state's measurements `m` (under the preparation model).
ProbeBasis probe_basis(const Setup& s, const ConfigState& c, const Measurements& m);

// The relative changes of K, G, M when the amplitude is halved at the same rate (_a) and when
// the rate is halved at the same amplitude (_r); NaN where not checked.
struct Halving {
  double dK_a = kNaN, dG_a = kNaN, dM_a = kNaN, dK_r = kNaN, dG_r = kNaN, dM_r = kNaN;
};

// What one probing model measured on a configuration, with the theories at its phi and Z.
struct ProbeResult {
  Moduli mod;
  double reversal = kNaN;  // isotropic reversal residual
  double kt_kn = 0;        // tangential over normal stiffness of the probing model
  TheoryResult th, thc;    // with the measured chi, and with the closure
  Halving halving;
};
// The table row of one probing model: `context` (the preparation's columns) and what was
// measured, the structure of the configuration included.
std::map<std::string, double> probe_row(const Setup& s, const ConfigState& c, const ProbeBasis& b,
                                        const ProbeResult& r,
                                        const std::map<std::string, double>& context);
// The console line of one probing model (`ratio`: its kt/kn, < 0 where the scene lists none).
void report_probe(const ProbeBasis& b, const ProbeResult& r, double ratio);

// Where a sweep of the configuration saved at `phi` goes: <kind>/<tag>_phi_<phi>.
std::string sweep_group(const std::string& kind, const std::string& tag, double phi);
// One amplitude of a sweep: the columns of `mod`, probed with `n` steps at inertial number I.
void add_sweep_point(std::map<std::string, std::vector<double>>& sw, double amplitude,
                     const Moduli& mod, double scale, double I, long n, double reversal);
// One pre-strain `e` of a reversibility test (mode 0 isotropic, 1 pure shear).
void add_reversibility_point(std::map<std::string, std::vector<double>>& rv, double e, int mode,
                             const Reversibility& r, double scale);

// The state's measurements and what its probes share.
template <class Model>
ProbeBasis probe_basis(const Setup& s, const ConfigState& c, const Model& prep_model) {
  Measurements m;
  {
    auto sys = restart_system<DemSystem<Exec, Model>>(c, prep_model, s.params);
    m = sys.measure();
  }
  return probe_basis(s, c, m);
}

// The halving check: half the amplitude at the same rate; the same amplitude at half the rate.
template <class Model>
Halving halving_check(const Setup& s, const ConfigState& c, const Model& model, long steps,
                      const Moduli& mod) {
  const Moduli ha = probe_config(c, model, s, s.amplitude / 2, std::max(1L, steps / 2), nullptr);
  const Moduli hr = probe_config(c, model, s, s.amplitude, 2 * steps, nullptr);
  Halving h;
  h.dK_a = rel_change(ha.K, mod.K), h.dG_a = rel_change(ha.G, mod.G),
  h.dM_a = rel_change(ha.M, mod.M);
  h.dK_r = rel_change(hr.K, mod.K), h.dG_r = rel_change(hr.G, mod.G),
  h.dM_r = rel_change(hr.M, mod.M);
  return h;
}

// Probes the configuration with `model` (a jammed one only) and evaluates the theories.
template <class Model>
ProbeResult probe_with(const Setup& s, const ConfigState& c, const ProbeBasis& b,
                       const Model& model, double ratio) {
  ProbeResult r;
  if (b.jammed) r.mod = probe_config(c, model, s, s.amplitude, b.steps, &r.reversal);
  r.kt_kn = stiffness_ratio(s.contact, b.kn, ratio);
  TheoryInput ti;
  ti.phi = b.m.phi, ti.z = b.m.z_corrected, ti.chi = b.m.chi, ti.kt_kn = r.kt_kn, ti.D = b.st.D;
  r.th = moduli_theory(ti);
  ti.chi = -1;
  r.thc = moduli_theory(ti);
  // Below jamming the relative change of the moduli under halving means nothing.
  if (s.halving && b.jammed) r.halving = halving_check(s, c, model, b.steps, r.mod);
  return r;
}

// Reversibility: pre-strains of growing size, isotropic and pure shear, each from the saved
// state relaxed further, then reversed (see probe_reversibility).
template <class Model>
SweepColumns reversibility_sweep(const Setup& s, const ConfigState& c, const Model& probe_base,
                                 const ProbeBasis& b, const std::string& tag) {
  std::map<std::string, std::vector<double>> rv;
  for (int mode = 0; mode < 2; ++mode)
    for (double e : s.prestrains) {
      auto sys = restart_system<DemSystem<Exec, Model>>(c, probe_base, s.params);
      const Reversibility r = probe_reversibility(
          sys, mode == 0 ? kIsotropic : kPureShear, e, s.amplitude, steps_for(s, e, b.base_rate),
          b.steps, s.probe_relax, s.prestrain_relax_ratio, s.relax_max);
      add_reversibility_point(rv, e, mode, r, b.scale);
      std::cerr << "  pre-strain " << e << (mode == 0 ? " isotropic" : " shear") << ": loading "
                << r.loading * b.scale << "  unloading " << r.unloading * b.scale << "  residual "
                << r.residual << "\n";
    }
  return {{sweep_group("/reversibility/", tag, c.phi), tag, b.m.phi, b.m.z_corrected}, rv};
}

// Amplitude sweep at the base probing rate (bounded step counts), from the same state.
// The amplitudes whose step count reaches the cap share one reference run.
template <class Model>
SweepColumns amplitude_sweep(const Setup& s, const ConfigState& c, const Model& probe_base,
                             const ProbeBasis& b, const std::string& tag) {
  std::map<std::string, std::vector<double>> sw;
  ReferenceRuns<DemSystem<Exec, Model>> references;
  for (double a : s.amplitudes) {
    // At the base rate (smaller amplitudes take fewer steps), or in the base probe's number of
    // steps (the rate scales with the amplitude: 100 times smaller amplitude and rate).
    const long n = s.sweep_same_steps ? b.steps : steps_for(s, a, b.base_rate);
    double reversal = 0;
    const Moduli mod = probe_config(c, probe_base, s, a, n, &reversal, &references);
    add_sweep_point(sw, a, mod, b.scale, a / (n * s.params.dt) * b.inertia_scale, n, reversal);
    std::cerr << "  sweep amplitude " << a << ": K* " << mod.K * b.scale << "  G* "
              << mod.G * b.scale << "  M* " << mod.M * b.scale << "\n";
  }
  return {{sweep_group("/sweep/", tag, c.phi), tag, b.m.phi, b.m.z_corrected}, sw};
}

// Everything measured on one configuration: a row per probing tangential stiffness, and the
// reversibility test and amplitude sweep where the scene asks for them (jammed states only).
template <class Model>
ConfigResults analyse(const Setup& s, const ConfigState& c, const Model& prep_model,
                      const std::map<std::string, double>& context, const std::string& tag) {
  const ProbeBasis b = probe_basis(s, c, prep_model);
  const Model probe_base = s.keep_friction ? prep_model : with_friction(prep_model, INFINITY);
  const std::vector<double> ratios = s.kt_ratios.empty() ? std::vector<double>{-1} : s.kt_ratios;
  ConfigResults out;
  for (double ratio : ratios) {
    const Model model =
        ratio >= 0 ? with_tangential_stiffness(probe_base, ratio * b.kn) : probe_base;
    const ProbeResult r = probe_with(s, c, b, model, ratio);
    out.rows.push_back({tag, probe_row(s, c, b, r, context)});
    report_probe(b, r, ratio);
  }
  if (!s.prestrains.empty() && b.jammed)
    out.sweeps.push_back(reversibility_sweep(s, c, probe_base, b, tag));
  if (!s.amplitudes.empty() && b.jammed)
    out.sweeps.push_back(amplitude_sweep(s, c, probe_base, b, tag));
  return out;
}

}  // namespace granular::moduli_study
