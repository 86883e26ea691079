// The host-side helpers of probing: size statistics and mean contact stiffnesses of a
// saved configuration, probing steps for a rate, and the table rows, sweep columns and
// console lines of what was probed.
#include "scenarios/moduli/moduli_probing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace granular::moduli_study {

SizeStats size_stats(const ConfigState& c) {
  double s1 = 0, s2 = 0, s3 = 0, rho = 0;
  const int n = c.size();
  for (int i = 0; i < n; ++i) {
    const double d = 2 * c.particles.radius[i];
    s1 += d, s2 += d * d, s3 += d * d * d, rho += c.particles.density[i];
  }
  return {s1 / n, rho / n, s2 / s3 * s1 / n};
}

double mean_normal_stiffness(const ConfigState& c, const ContactConfig& cc) {
  if (cc.normal == "linear") return cc.linear.kn;
  if (cc.normal == "hysteretic") return cc.hysteretic.k2;
  const HostParticles& p = c.particles;
  double sum = 0, count = 0;
  for (int i = 0; i < c.size(); ++i)
    for (int j = i + 1; j < c.size(); ++j) {
      const double r[3] = {c.box.min_image(p.x[i] - p.x[j], 0), c.box.min_image(p.y[i] - p.y[j], 1),
                           c.box.min_image(p.z[i] - p.z[j], 2)};
      const double ai = p.radius[i], aj = p.radius[j];
      const double delta = ai + aj - std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      if (delta <= 0) continue;
      const double L = cc.hertz.reduced_radius ? ai * aj / (ai + aj) : ai + aj;
      sum += 1.5 * cc.hertz.K * std::sqrt(L * delta), count += 1;
    }
  return count > 0 ? sum / count : kNaN;
}

double stiffness_ratio(const ContactConfig& cc, double kn_mean, double kt_override) {
  if (cc.tangential != "coulomb") return 0.0;
  if (kt_override >= 0) return kt_override;
  if (cc.coulomb.law == 0) return cc.coulomb.kt / kn_mean;
  // Mindlin spring kt sqrt(L delta) against Hertz 1.5 K sqrt(L delta), the same L.
  return cc.normal == "hertz" ? cc.coulomb.kt / (1.5 * cc.hertz.K) : kNaN;
}

long steps_for(const Setup& s, double amplitude, double base_rate) {
  const double steps = amplitude / (base_rate * s.params.dt);
  // max_strain_steps >= 20 is checked on read, but a variant's own dt rescales it.
  return std::clamp(static_cast<long>(std::ceil(steps)), 20L, std::max(20L, s.max_strain_steps));
}

double rel_change(double a, double b) { return std::fabs(a / b - 1.0); }

ProbeBasis probe_basis(const Setup& s, const ConfigState& c, const Measurements& m) {
  ProbeBasis b;
  b.st = size_stats(c);
  b.kn = mean_normal_stiffness(c, s.contact);
  b.scale = b.st.dbar / b.kn;
  b.m = m;
  const double P = m.pressure;
  b.inertia_scale = P > 0 ? b.st.dbar * std::sqrt(b.st.density / P) : kNaN;
  // Axial probing rate: from the target inertial number, else amplitude / strain_steps.
  b.base_rate = s.probe_inertial > 0 && P > 0 ? s.probe_inertial / b.inertia_scale
                                              : s.amplitude / (s.strain_steps * s.params.dt);
  b.steps = s.probe_inertial > 0 ? steps_for(s, s.amplitude, b.base_rate) : s.strain_steps;
  b.probe_I = s.amplitude / (b.steps * s.params.dt) * b.inertia_scale;
  b.jammed = is_jammed(m);
  return b;
}

namespace {
// The state's own columns and its moduli, partitions and fluctuations.
std::map<std::string, double> measured_columns(const ConfigState& c, const ProbeBasis& b,
                                               const ProbeResult& r) {
  const Measurements& m = b.m;
  const Moduli& mod = r.mod;
  const double scale = b.scale;
  return {{"particles", static_cast<double>(c.size())},
          {"jammed", b.jammed ? 1.0 : 0.0},
          {"phi", m.phi},
          {"z_corrected", m.z_corrected},
          {"chi", m.chi},
          {"rattler_fraction", m.rattlers / c.size()},
          {"pressure_star", m.pressure * scale},
          {"kn_mean", b.kn},
          {"kt_kn", r.kt_kn},
          {"inertial_number_probe", b.probe_I},
          {"probe_strain_steps", static_cast<double>(b.steps)},
          {"K_star", mod.K * scale},
          {"G_star", mod.G * scale},
          {"M_star", mod.M * scale},
          {"K_n_star", mod.K_n * scale},
          {"K_t_star", mod.K_t * scale},
          {"G_n_star", mod.G_n * scale},
          {"G_t_star", mod.G_t * scale},
          {"M_over_K_plus_4G_3", mod.M / (mod.K + 4 * mod.G / 3)},
          {"isotropic_reversal_residual", r.reversal},
          {"eta_K", mod.eta_K},
          {"eta_G", mod.eta_G},
          {"eta_M", mod.eta_M},
          {"eta_K_per_contact", mod.eta_K_per_contact},
          {"eta_K_normal", mod.eta_K_normal},
          {"normal_relaxation_K", mod.normal_relaxation_K}};
}

// The halving check's relative changes and the theories' moduli.
std::map<std::string, double> check_and_theory_columns(const ProbeResult& r) {
  const Halving& h = r.halving;
  return {{"halving_amplitude_rel_change_K", h.dK_a},
          {"halving_amplitude_rel_change_G", h.dG_a},
          {"halving_amplitude_rel_change_M", h.dM_a},
          {"halving_rate_rel_change_K", h.dK_r},
          {"halving_rate_rel_change_G", h.dG_r},
          {"halving_rate_rel_change_M", h.dM_r},
          {"K_emt", r.th.K_emt},
          {"G_emt", r.th.G_emt},
          {"K_ft1", r.th.K_ft1},
          {"G_ft1", r.th.G_ft1},
          {"K_ft2", r.th.K_ft2},
          {"G_ft2", r.th.G_ft2},
          {"K_ft2_closure", r.thc.K_ft2},
          {"G_ft2_closure", r.thc.G_ft2},
          {"rho", r.th.rho},
          {"rho_s", r.th.rho_s},
          {"zeta", r.th.zeta}};
}

// Structure of the configuration: contact-number histogram, fabric tensor, and the pressure
// carried by normal and by tangential contact forces.
void add_structure_columns(const Setup& s, const ProbeBasis& b,
                           std::map<std::string, double>& row) {
  const Measurements& m = b.m;
  const char* comp[6] = {"xx", "yy", "zz", "xy", "xz", "yz"};
  for (int q = 0; q < 7; ++q)
    row["contact_fraction_" + std::to_string(q) + (q == 6 ? "_or_more" : "")] =
        m.contact_histogram[q];
  for (int q = 0; q < 6; ++q) row[std::string("fabric_") + comp[q]] = m.fabric[q];
  // The source's normalisation of the cohesive set, P / k* with k* = k1 / (2<a>) (the
  // engine's P* divides by k2 / dbar, the un/reloading stiffness).
  if (s.contact.normal == "hysteretic")
    row["pressure_over_k1_star"] = m.pressure * b.st.dbar / s.contact.hysteretic.k1;
  row["pressure_normal_star"] =
      (m.stress_normal[0] + m.stress_normal[1] + m.stress_normal[2]) / 3 * b.scale;
  row["pressure_tangential_star"] =
      (m.stress_tangential[0] + m.stress_tangential[1] + m.stress_tangential[2]) / 3 * b.scale;
}
}  // namespace

std::map<std::string, double> probe_row(const Setup& s, const ConfigState& c, const ProbeBasis& b,
                                        const ProbeResult& r,
                                        const std::map<std::string, double>& context) {
  std::map<std::string, double> row = context;
  // insert keeps what `context` holds; the two never share a column.
  const std::map<std::string, double> measured = measured_columns(c, b, r);
  const std::map<std::string, double> checks = check_and_theory_columns(r);
  row.insert(measured.begin(), measured.end());
  row.insert(checks.begin(), checks.end());
  add_structure_columns(s, b, row);
  return row;
}

void report_probe(const ProbeBasis& b, const ProbeResult& r, double ratio) {
  const Measurements& m = b.m;
  const Moduli& mod = r.mod;
  std::cerr << "phi " << m.phi << (ratio >= 0 ? "  kt/kn " + std::to_string(ratio) : "") << ": Z "
            << m.z_corrected;
  if (b.jammed)
    std::cerr << "  K* " << mod.K * b.scale << "  G* " << mod.G * b.scale << "  M/(K+4G/3) "
              << mod.M / (mod.K + 4 * mod.G / 3) << "  eta_K " << mod.eta_K << "  I " << b.probe_I
              << "\n";
  else
    std::cerr << "  rattlers " << m.rattlers << " of " << m.particles
              << "  (unjammed: no load-bearing contact network, not probed)\n";
}

std::string sweep_group(const std::string& kind, const std::string& tag, double phi) {
  char name[64];
  std::snprintf(name, sizeof name, "phi_%.4f", phi);
  return kind + (tag.empty() ? "" : tag + "_") + name;
}

void add_sweep_point(std::map<std::string, std::vector<double>>& sw, double amplitude,
                     const Moduli& mod, double scale, double I, long n, double reversal) {
  const double vals[] = {amplitude,
                         mod.K * scale,
                         mod.G * scale,
                         mod.M * scale,
                         mod.eta_K,
                         mod.eta_G,
                         mod.eta_M,
                         I,
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
}

void add_reversibility_point(std::map<std::string, std::vector<double>>& rv, double e, int mode,
                             const Reversibility& r, double scale) {
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
}

}  // namespace granular::moduli_study
