// Probing one configuration of the elastic_moduli study: the probing model (friction and
// tangential stiffness of the preparation or of the scene), K, G, M with their partitions
// and non-affine fluctuation, the theories at the same phi Z, the rate/amplitude halving
// check and amplitude sweeps; each configuration's rows go to the study's outputs.
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

// Everything measured on one configuration; rows appended to `out`.
template <class Model>
void analyse(const Setup& s, const ConfigState& c, const Model& prep_model,
             const std::map<std::string, double>& context, const std::string& tag, Outputs& out) {
  const SizeStats st = size_stats(c);
  const double kn = mean_normal_stiffness(c, s.contact);
  const double scale = st.dbar / kn;
  Measurements m;
  {
    auto sys = restart_system<DemSystem<Exec, Model>>(c, prep_model, s.params);
    m = sys.measure();
  }
  const double P = m.pressure;
  const double inertia_scale = P > 0 ? st.dbar * std::sqrt(st.density / P) : kNaN;
  // Axial probing rate: from the target inertial number, else amplitude / strain_steps.
  const double base_rate = s.probe_inertial > 0 && P > 0
                               ? s.probe_inertial / inertia_scale
                               : s.amplitude / (s.strain_steps * s.params.dt);
  const long steps = s.probe_inertial > 0 ? steps_for(s, s.amplitude, base_rate) : s.strain_steps;
  const double probe_I = s.amplitude / (steps * s.params.dt) * inertia_scale;
  const Model probe_base = s.keep_friction ? prep_model : with_friction(prep_model, INFINITY);
  const std::vector<double> ratios = s.kt_ratios.empty() ? std::vector<double>{-1} : s.kt_ratios;
  // Below jamming the moduli vanish: probing such a state only measures the drift of a
  // dissolving network (at the inertial-number rate of its tiny pressure, minutes per mode),
  // so it is left out and its moduli are reported as zero.
  const bool jammed = is_jammed(m);
  for (double ratio : ratios) {
    const Model model = ratio >= 0 ? with_tangential_stiffness(probe_base, ratio * kn) : probe_base;
    double reversal = kNaN;
    const Moduli mod = jammed ? probe_config(c, model, s, s.amplitude, steps, &reversal) : Moduli{};
    std::map<std::string, double> row = context;
    const double kt_kn = stiffness_ratio(s.contact, kn, ratio);
    TheoryInput ti;
    ti.phi = m.phi, ti.z = m.z_corrected, ti.chi = m.chi, ti.kt_kn = kt_kn, ti.D = st.D;
    const TheoryResult th = moduli_theory(ti);
    ti.chi = -1;
    const TheoryResult thc = moduli_theory(ti);
    double dK_a = kNaN, dG_a = kNaN, dM_a = kNaN, dK_r = kNaN, dG_r = kNaN, dM_r = kNaN;
    // Below jamming the relative change of the moduli under halving means nothing.
    // Halving: half the amplitude at the same rate; the same amplitude at half the rate.
    if (s.halving && jammed) {
      const Moduli ha =
          probe_config(c, model, s, s.amplitude / 2, std::max(1L, steps / 2), nullptr);
      const Moduli hr = probe_config(c, model, s, s.amplitude, 2 * steps, nullptr);
      dK_a = rel_change(ha.K, mod.K), dG_a = rel_change(ha.G, mod.G),
      dM_a = rel_change(ha.M, mod.M);
      dK_r = rel_change(hr.K, mod.K), dG_r = rel_change(hr.G, mod.G),
      dM_r = rel_change(hr.M, mod.M);
    }
    const std::map<std::string, double> values = {
        {"particles", static_cast<double>(c.size())},
        {"jammed", jammed ? 1.0 : 0.0},
        {"phi", m.phi},
        {"z_corrected", m.z_corrected},
        {"chi", m.chi},
        {"rattler_fraction", m.rattlers / c.size()},
        {"pressure_star", m.pressure * scale},
        {"kn_mean", kn},
        {"kt_kn", kt_kn},
        {"inertial_number_probe", probe_I},
        {"probe_strain_steps", static_cast<double>(steps)},
        {"K_star", mod.K * scale},
        {"G_star", mod.G * scale},
        {"M_star", mod.M * scale},
        {"K_n_star", mod.K_n * scale},
        {"K_t_star", mod.K_t * scale},
        {"G_n_star", mod.G_n * scale},
        {"G_t_star", mod.G_t * scale},
        {"M_over_K_plus_4G_3", mod.M / (mod.K + 4 * mod.G / 3)},
        {"isotropic_reversal_residual", reversal},
        {"eta_K", mod.eta_K},
        {"eta_G", mod.eta_G},
        {"eta_M", mod.eta_M},
        {"eta_K_per_contact", mod.eta_K_per_contact},
        {"eta_K_normal", mod.eta_K_normal},
        {"normal_relaxation_K", mod.normal_relaxation_K},
        {"halving_amplitude_rel_change_K", dK_a},
        {"halving_amplitude_rel_change_G", dG_a},
        {"halving_amplitude_rel_change_M", dM_a},
        {"halving_rate_rel_change_K", dK_r},
        {"halving_rate_rel_change_G", dG_r},
        {"halving_rate_rel_change_M", dM_r},
        {"K_emt", th.K_emt},
        {"G_emt", th.G_emt},
        {"K_ft1", th.K_ft1},
        {"G_ft1", th.G_ft1},
        {"K_ft2", th.K_ft2},
        {"G_ft2", th.G_ft2},
        {"K_ft2_closure", thc.K_ft2},
        {"G_ft2_closure", thc.G_ft2},
        {"rho", th.rho},
        {"rho_s", th.rho_s},
        {"zeta", th.zeta}};
    row.insert(values.begin(), values.end());
    // Structure of the configuration: contact-number histogram, fabric tensor, and the
    // pressure carried by normal and by tangential contact forces.
    const char* comp[6] = {"xx", "yy", "zz", "xy", "xz", "yz"};
    for (int q = 0; q < 7; ++q)
      row["contact_fraction_" + std::to_string(q) + (q == 6 ? "_or_more" : "")] =
          m.contact_histogram[q];
    for (int q = 0; q < 6; ++q) row[std::string("fabric_") + comp[q]] = m.fabric[q];
    // The source's normalisation of the cohesive set, P / k* with k* = k1 / (2<a>) (the
    // engine's P* divides by k2 / dbar, the un/reloading stiffness).
    if (s.contact.normal == "hysteretic")
      row["pressure_over_k1_star"] = m.pressure * st.dbar / s.contact.hysteretic.k1;
    row["pressure_normal_star"] =
        (m.stress_normal[0] + m.stress_normal[1] + m.stress_normal[2]) / 3 * scale;
    row["pressure_tangential_star"] =
        (m.stress_tangential[0] + m.stress_tangential[1] + m.stress_tangential[2]) / 3 * scale;
    out.add_row(tag, row);
    std::cerr << "phi " << m.phi << (ratio >= 0 ? "  kt/kn " + std::to_string(ratio) : "") << ": Z "
              << m.z_corrected;
    if (jammed)
      std::cerr << "  K* " << mod.K * scale << "  G* " << mod.G * scale << "  M/(K+4G/3) "
                << mod.M / (mod.K + 4 * mod.G / 3) << "  eta_K " << mod.eta_K << "  I " << probe_I
                << "\n";
    else
      std::cerr << "  rattlers " << m.rattlers << " of " << m.particles
                << "  (unjammed: no load-bearing contact network, not probed)\n";
  }
  if (!s.prestrains.empty() && jammed) {
    // Reversibility: pre-strains of growing size, isotropic and pure shear, each from the
    // saved state relaxed further, then reversed (see probe_reversibility).
    std::map<std::string, std::vector<double>> rv;
    for (int mode = 0; mode < 2; ++mode)
      for (double e : s.prestrains) {
        auto sys = restart_system<DemSystem<Exec, Model>>(c, probe_base, s.params);
        const Reversibility r = probe_reversibility(
            sys, mode == 0 ? kIsotropic : kPureShear, e, s.amplitude, steps_for(s, e, base_rate),
            steps, s.probe_relax, s.prestrain_relax_ratio, s.relax_max);
        const double vals[] = {e,
                               static_cast<double>(mode),
                               r.loading * scale,
                               r.unloading * scale,
                               r.residual,
                               r.relaxed_ratio};
        const char* names[] = {"prestrain",
                               "mode",
                               "loading_modulus_star",
                               "unloading_modulus_star",
                               "residual",
                               "relaxed_ekin_over_epot"};
        for (size_t q = 0; q < std::size(vals); ++q) rv[names[q]].push_back(vals[q]);
        std::cerr << "  pre-strain " << e << (mode == 0 ? " isotropic" : " shear") << ": loading "
                  << r.loading * scale << "  unloading " << r.unloading * scale << "  residual "
                  << r.residual << "\n";
      }
    char name[64];
    std::snprintf(name, sizeof name, "phi_%.4f", c.phi);
    out.add_sweep(
        {"/reversibility/" + (tag.empty() ? "" : tag + "_") + name, tag, m.phi, m.z_corrected}, rv);
  }
  if (s.amplitudes.empty() || !jammed) return;
  // Amplitude sweep at the base probing rate (bounded step counts), from the same state.
  // The amplitudes whose step count reaches the cap share one reference run.
  std::map<std::string, std::vector<double>> sw;
  ReferenceRuns<DemSystem<Exec, Model>> references;
  for (double a : s.amplitudes) {
    // At the base rate (smaller amplitudes take fewer steps), or in the base probe's number of
    // steps (the rate scales with the amplitude: 100 times smaller amplitude and rate).
    const long n = s.sweep_same_steps ? steps : steps_for(s, a, base_rate);
    double reversal = 0;
    const Moduli mod = probe_config(c, probe_base, s, a, n, &reversal, &references);
    const double vals[] = {a,
                           mod.K * scale,
                           mod.G * scale,
                           mod.M * scale,
                           mod.eta_K,
                           mod.eta_G,
                           mod.eta_M,
                           a / (n * s.params.dt) * inertia_scale,
                           static_cast<double>(n),
                           reversal,
                           mod.fabric_v_change_K,
                           mod.fabric_v_change_G,
                           mod.fabric_dev_change_G};
    const char* names[] = {"amplitude",
                           "K_star",
                           "G_star",
                           "M_star",
                           "eta_K",
                           "eta_G",
                           "eta_M",
                           "inertial_number",
                           "strain_steps",
                           "reversal_residual",
                           "fabric_v_change_K",
                           "fabric_v_change_G",
                           "fabric_dev_change_G"};
    for (size_t q = 0; q < std::size(vals); ++q) sw[names[q]].push_back(vals[q]);
    std::cerr << "  sweep amplitude " << a << ": K* " << mod.K * scale << "  G* " << mod.G * scale
              << "  M* " << mod.M * scale << "\n";
  }
  char name[64];
  std::snprintf(name, sizeof name, "phi_%.4f", c.phi);
  const std::string group = "/sweep/" + (tag.empty() ? "" : tag + "_") + name;
  out.add_sweep({group, tag, m.phi, m.z_corrected}, sw);
}

}  // namespace granular::moduli_study
