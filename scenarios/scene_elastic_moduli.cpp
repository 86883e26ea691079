// Scene `elastic_moduli`: the preparation protocol of dem.md section 6 (gas -> compress to
// phi_0 -> relax -> compress to phi_max -> decompress), configurations saved on the chosen
// branch at the listed volume fractions, relaxed and written as restartable HDF5 files
// (configs/), then elastic probing of each (sliding switched off unless the scene keeps
// friction): K*, G*, M*, partitions, non-affine fluctuation and inertial numbers against
// phi Z next to effective-medium and fluctuation theory, in a table, charts and summary.json.
// One driver covers the studies through scene keys: preparation friction list, ensembles
// of sizes and seeds, probing tangential stiffness list, amplitude sweeps, the rate and
// amplitude halving check, and probing saved configurations ([start] from).
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <optional>

#include "core/output.hpp"
#include "core/progress.hpp"
#include "scenarios/config_state.hpp"
#include "scenarios/contact_config.hpp"
#include "scenarios/element_test.hpp"
#include "scenarios/moduli_outputs.hpp"
#include "scenarios/moduli_theory.hpp"
#include "scenarios/packing.hpp"
#include "scenarios/run_report.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {
using Exec = Kokkos::DefaultExecutionSpace;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The same contact model with another friction coefficient (infinity: no sliding).
template <class Model>
Model with_friction(Model m, double mu) {
  if constexpr (Model::tangential_type::active) {
    for (auto& row : m.tangential.table.p)
      for (auto& q : row) q.mu_s = q.mu_d = mu;
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

// One preparation of the protocol: its size, seed and friction.
struct PrepVariant {
  int count = 0;
  std::uint64_t seed = 1;
  double mu = kNaN;  // preparation friction (NaN: as in [contact])
  std::string tag;   // subdirectory of configs/ and label in the table ("" if only one)
};

struct Setup {
  GasSpec gas;
  ContactConfig contact;
  DemParams params;
  std::vector<PrepVariant> variants;
  std::string start_from;  // probe this saved configuration instead of preparing
  double phi0 = 0.5, phi_max = 0.82, rate = 0, min_rate = 0, prep_inertial = 0, gas_rate = 0;
  bool loading_branch = false;
  std::vector<double> targets;
  double relax_ratio = 1e-8;
  long relax_max = 200000;
  double amplitude = 3e-6, probe_inertial = 0;
  long strain_steps = 2000, probe_relax = 2000, max_strain_steps = 200000;
  bool keep_friction = false, halving = false;
  int orientations = 1;  // shear planes and uniaxial axes probed (1: xy and x; 3: all)
  // How much of the preparation this run does before it stops at a checkpoint (0: all):
  // variants, stages (a 0.02 step in phi, a relaxation or a saved configuration).
  long stop_after_variants = 0, stop_after_stages = 0;
  std::vector<double> kt_ratios;   // probing tangential stiffness over normal (empty: as prepared)
  std::vector<double> amplitudes;  // amplitude sweep (empty: none)
};

Setup read_setup(const SceneFile& scene) {
  Setup s;
  s.start_from = scene.text("start.from", "");
  s.contact = ContactConfig::read(scene);
  s.params.dt = scene.real("run.dt");
  s.params.skin = scene.real("run.skin");
  s.params.damping.translational = scene.real("damping.background", 0.0);
  s.params.damping.rotational = scene.real("damping.rotational", 0.0);
  s.params.rattler_threshold = static_cast<int>(scene.integer("run.rattler_threshold", 3));
  s.params.max_overlap = scene.real("run.max_overlap", 0.5);
  s.stop_after_variants = scene.integer("run.stop_after_variants", 0);
  s.stop_after_stages = scene.integer("run.stop_after_stages", 0);
  scene.require(s.stop_after_variants >= 0, "run.stop_after_variants", "must not be negative");
  scene.require(s.stop_after_stages >= 0, "run.stop_after_stages", "must not be negative");
  s.relax_ratio = scene.real("preparation.relax_ratio", 1e-8);
  s.relax_max = scene.integer("preparation.relax_max_steps", 200000);
  s.amplitude = scene.real("probe.amplitude", 3e-6);
  s.strain_steps = scene.integer("probe.strain_steps", 2000);
  s.probe_relax = scene.integer("probe.relax_steps", 2000);
  s.probe_inertial = scene.real("probe.inertial_number", 0.0);
  s.max_strain_steps = scene.integer("probe.max_strain_steps", 200000);
  s.keep_friction = scene.flag("probe.keep_friction", false);
  s.halving = scene.flag("probe.halving_check", false);
  s.orientations = static_cast<int>(scene.integer("probe.orientations", 1));
  scene.require(s.orientations == 1 || s.orientations == 3, "probe.orientations",
                "must be 1 (shear in xy, uniaxial along x) or 3 (all planes and axes, averaged)");
  s.kt_ratios = scene.reals("probe.kt_over_kn", {});
  s.amplitudes = scene.reals("probe.amplitudes", {});
  scene.require(s.amplitude > 0 && s.amplitude < 1e-2, "probe.amplitude", "must be in (0, 1e-2)");
  scene.require(s.strain_steps > 0 && s.probe_relax >= 0, "probe.strain_steps",
                "and probe.relax_steps must be positive");
  scene.require(s.probe_inertial >= 0 && s.probe_inertial < 1e-2, "probe.inertial_number",
                "must be in [0, 1e-2) (quasi-static probing: 1e-4 ... 1e-6)");
  for (double a : s.amplitudes)
    scene.require(a > 0 && a <= 0.05, "probe.amplitudes", "must lie in (0, 0.05]");
  for (double r : s.kt_ratios) scene.require(r >= 0, "probe.kt_over_kn", "must not be negative");
  if (!s.kt_ratios.empty())
    scene.require(s.contact.tangential == "coulomb" && s.contact.coulomb.law == 0 &&
                      s.contact.normal != "hertz",
                  "probe.kt_over_kn",
                  "needs a linear or hysteretic normal law with a constant tangential spring");
  if (!s.start_from.empty()) {
    s.variants.push_back({});
    scene.reject_unknown_keys();
    return s;
  }
  GasSpec& g = s.gas;
  const long count = scene.integer("particles.count", 0);
  scene.require(count >= 0 && count <= std::numeric_limits<int>::max(), "particles.count",
                "must be in [2, 2^31)");
  g.count = static_cast<int>(count);
  g.diameter_min = scene.real("particles.diameter_min");
  g.diameter_max = scene.real("particles.diameter_max");
  g.density = scene.real("particles.density");
  g.seed = static_cast<std::uint64_t>(scene.integer("particles.seed", 1));
  g.speed = scene.real("particles.initial_speed", 0.0);
  g.phi = scene.real("preparation.phi_gas", 0.3);
  s.phi0 = scene.real("preparation.phi_0", 0.5);
  s.phi_max = scene.real("preparation.phi_max");
  s.rate = scene.real("preparation.volumetric_strain_rate");
  s.prep_inertial = scene.real("preparation.inertial_number", 0.0);
  s.min_rate = scene.real("preparation.min_volumetric_strain_rate", s.rate / 20);
  // The gas below phi_0 has no contact network to keep quasi-static (its pressure is tiny,
  // so an inertial-number rule would crawl at the minimum rate) and is relaxed to zero
  // pressure afterwards: it is compressed at this constant rate.
  s.gas_rate = scene.real("preparation.gas_strain_rate", s.rate);
  scene.require(s.gas_rate > 0, "preparation.gas_strain_rate", "must be positive");
  const std::string branch = scene.text("preparation.branch", "unloading");
  scene.require(branch == "unloading" || branch == "loading", "preparation.branch",
                "must be \"unloading\" (decompression from phi_max) or \"loading\"");
  s.loading_branch = branch == "loading";
  s.targets = scene.reals("preparation.targets");
  check_gas(scene, g, "preparation.phi_gas");
  scene.require(s.phi0 > g.phi && s.phi_max > s.phi0 && s.phi_max < 1, "preparation.phi_max",
                "must satisfy phi_gas < phi_0 < phi_max < 1");
  for (double t : s.targets)
    scene.require(t > s.phi0 && t < s.phi_max, "preparation.targets",
                  "must lie between phi_0 and phi_max");
  scene.require(s.rate > 0, "preparation.volumetric_strain_rate", "must be positive");
  scene.require(s.min_rate > 0 && s.min_rate <= s.rate, "preparation.min_volumetric_strain_rate",
                "must be in (0, preparation.volumetric_strain_rate]");
  // Preparation variants: sizes x seeds x friction coefficients.
  std::vector<double> counts = scene.reals("ensemble.counts", {});
  std::vector<double> seeds = scene.reals("ensemble.seeds", {});
  const std::vector<double> mus = scene.reals("preparation.mu", {});
  if (counts.empty()) counts.push_back(g.count);
  if (seeds.empty()) seeds.push_back(static_cast<double>(g.seed));
  for (double c : counts) {
    scene.require(c >= 2 && c <= std::numeric_limits<int>::max(), "particles.count",
                  "(or ensemble.counts) must be in [2, 2^31)");
    scene.require_memory("particles.count", c * kDemBytesPerParticle);
  }
  for (double m : mus) scene.require(m >= 0, "preparation.mu", "must not be negative");
  if (!mus.empty())
    scene.require(s.contact.tangential == "coulomb", "preparation.mu",
                  "needs contact.tangential = \"coulomb\"");
  const std::vector<double> mu_list = mus.empty() ? std::vector<double>{kNaN} : mus;
  for (double c : counts)
    for (double sd : seeds)
      for (double mu : mu_list) {
        PrepVariant v;
        v.count = static_cast<int>(c), v.seed = static_cast<std::uint64_t>(sd), v.mu = mu;
        char buf[96] = "";
        if (counts.size() > 1 || seeds.size() > 1)
          std::snprintf(buf, sizeof buf, "N%d_seed%d", v.count, static_cast<int>(sd));
        if (mus.size() > 1)
          std::snprintf(buf + std::strlen(buf), sizeof buf - std::strlen(buf), "%smu%g",
                        buf[0] ? "_" : "", mu);
        v.tag = buf;
        s.variants.push_back(v);
      }
  scene.reject_unknown_keys();
  return s;
}

// Mean diameter, density and size moment D = <d^2>/<d^3> dbar of a configuration.
struct SizeStats {
  double dbar = 0, density = 0, D = 0;
};
SizeStats size_stats(const ConfigState& c) {
  double s1 = 0, s2 = 0, s3 = 0, rho = 0;
  const int n = c.size();
  for (int i = 0; i < n; ++i) {
    const double d = 2 * c.particles.radius[i];
    s1 += d, s2 += d * d, s3 += d * d * d, rho += c.particles.density[i];
  }
  return {s1 / n, rho / n, s2 / s3 * s1 / n};
}

// Mean normal tangent stiffness dF/d(delta) over the contacts of a configuration (the k_n
// of the dimensionless moduli): k_n (linear), k2 (hysteretic, the un/reloading branch),
// 1.5 K sqrt(L delta) (Hertz). Host code, all pairs: it runs once per configuration.
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

// Tangential over normal tangent stiffness of the probing model, for the theories.
double stiffness_ratio(const ContactConfig& cc, double kn_mean, double kt_override) {
  if (cc.tangential != "coulomb") return 0.0;
  if (kt_override >= 0) return kt_override;
  if (cc.coulomb.law == 0) return cc.coulomb.kt / kn_mean;
  // Mindlin spring kt sqrt(L delta) against Hertz 1.5 K sqrt(L delta), the same L.
  return cc.normal == "hertz" ? cc.coulomb.kt / (1.5 * cc.hertz.K) : kNaN;
}

// Strain steps that give an axial probing rate I sqrt(P / rho) / dbar (inertial number I).
long steps_for(const Setup& s, double amplitude, double base_rate) {
  const double steps = amplitude / (base_rate * s.params.dt);
  return std::clamp(static_cast<long>(std::ceil(steps)), 20L, s.max_strain_steps);
}

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

double rel_change(double a, double b) { return std::fabs(a / b - 1.0); }

using Outputs = ModuliOutputs;

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
        {"zeta", th.zeta}};
    row.insert(values.begin(), values.end());
    // Structure of the configuration: contact-number histogram, fabric tensor, and the
    // pressure carried by normal and by tangential contact forces.
    const char* comp[6] = {"xx", "yy", "zz", "xy", "xz", "yz"};
    for (int q = 0; q < 7; ++q)
      row["contact_fraction_" + std::to_string(q) + (q == 6 ? "_or_more" : "")] =
          m.contact_histogram[q];
    for (int q = 0; q < 6; ++q) row[std::string("fabric_") + comp[q]] = m.fabric[q];
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
  if (s.amplitudes.empty() || !jammed) return;
  // Amplitude sweep at the base probing rate (bounded step counts), from the same state.
  // The amplitudes whose step count reaches the cap share one reference run.
  std::map<std::string, std::vector<double>> sw;
  ReferenceRuns<DemSystem<Exec, Model>> references;
  for (double a : s.amplitudes) {
    const long n = steps_for(s, a, base_rate);
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
                           reversal};
    const char* names[] = {
        "amplitude", "K_star", "G_star",          "M_star",       "eta_K",
        "eta_G",     "eta_M",  "inertial_number", "strain_steps", "reversal_residual"};
    for (size_t q = 0; q < std::size(vals); ++q) sw[names[q]].push_back(vals[q]);
    std::cerr << "  sweep amplitude " << a << ": K* " << mod.K * scale << "  G* " << mod.G * scale
              << "  M* " << mod.M * scale << "\n";
  }
  char name[64];
  std::snprintf(name, sizeof name, "phi_%.4f", c.phi);
  const std::string group = "/sweep/" + (tag.empty() ? "" : tag + "_") + name;
  out.add_sweep({group, tag, m.phi, m.z_corrected}, sw);
}

// Where a variant's preparation checkpoints its stages: "<dir>/<name>_stage" holds the
// number of the last finished stage k, "<name>_stage<k>_state.h5" the state after it and the
// part "<name>_stage<k>" the outputs so far (written before the number, so the number
// never points at an incomplete checkpoint).
struct StageCheckpoints {
  std::string dir, name, fingerprint;
  bool resume = false;
  std::string state(long k) const {
    return dir + "/" + name + "_stage" + std::to_string(k) + "_state.h5";
  }
  // The system's exact state after stage k (DemSystem::save_restart).
  std::string restart(long k) const {
    return dir + "/" + name + "_stage" + std::to_string(k) + "_restart.h5";
  }
  std::string part(long k) const { return name + "_stage" + std::to_string(k); }
  std::string pointer() const { return dir + "/" + name + "_stage"; }
  void remove(long k) const {
    if (k < 0) return;
    for (const std::string& f :
         {state(k), restart(k), dir + "/" + part(k) + ".h5", dir + "/" + part(k) + ".index"})
      std::filesystem::remove(f);
  }
};

// Runs the protocol for one variant, calling `on_config` with each relaxed configuration.
// The protocol is a list of stages (strains cut at every 0.02 in phi, relaxations, saved
// configurations); after each one the exact state and the outputs so far are checkpointed
// without touching the system, so the trajectory does not depend on where the stages fall,
// and a run resumed from any stage repeats the uninterrupted one bit for bit.
// Returns false when `stop` asked to end the run at a checkpoint.
template <class Model>
bool prepare(const Setup& s, const PrepVariant& v, const Model& model, Outputs& out,
             Progress& progress, long& done, const StageCheckpoints& ck,
             const std::function<bool()>& stop,
             const std::function<void(const ConfigState&, double, double)>& on_config) {
  GasSpec gas = s.gas;
  gas.count = v.count, gas.seed = v.seed;
  PeriodicBox box;
  const HostParticles host = random_gas(gas, box);
  double dsum = 0;
  for (double a : host.radius) dsum += 2 * a;
  const double dbar = dsum / host.size();
  using System = DemSystem<Exec, Model>;
  std::optional<System> sys;
  sys.emplace(Particles<Exec>::from_host(host), box, model, s.params);
  double rate_now = s.rate;
  // Volumetric rate for the target inertial number, within [min_rate, rate].
  auto rate_of = [&](const Measurements& m) {
    double r = s.rate;
    if (s.prep_inertial > 0 && m.pressure > 0)
      r = std::clamp(s.prep_inertial * std::sqrt(m.pressure / gas.density) / dbar, s.min_rate,
                     s.rate);
    return rate_now = r;
  };
  auto sample = [&](const Measurements& m) {
    out.prep["phi"].push_back(m.phi), out.prep["pressure"].push_back(m.pressure);
    out.prep["z_corrected"].push_back(m.z_corrected);
    out.prep["volumetric_strain_rate"].push_back(rate_now);
    out.prep["inertial_number"].push_back(
        m.pressure > 0 ? rate_now * dbar * std::sqrt(gas.density / m.pressure) : kNaN);
    out.prep["variant"].push_back(static_cast<double>(&v - s.variants.data()));
  };
  auto strain = [&](double target, double sign) {
    rate_now = s.rate;  // what the recorded series and I report (rate_of lowers it if adaptive)
    std::function<double(const Measurements&)> f = nullptr;
    if (s.prep_inertial > 0) f = [&, sign](const Measurements& m) { return sign * rate_of(m) / 3; };
    strain_to_phi(*sys, target, sign * s.rate / 3, 500, sample, f);
  };
  auto compress_gas = [&](double target) {
    rate_now = s.gas_rate;
    strain_to_phi(*sys, target, -s.gas_rate / 3, 500, sample);
  };
  auto save = [&] {
    const double ratio = relax(*sys, s.relax_ratio, s.relax_max, true);
    const Measurements m = sys->measure();
    const double I = m.pressure > 0 ? rate_now * dbar * std::sqrt(gas.density / m.pressure) : kNaN;
    on_config(snapshot(*sys, host.density, m.pressure), ratio, I);
  };
  // The stages: work, and whether it ends a step of the protocol (for the progress line).
  std::vector<std::pair<std::function<void()>, bool>> stages;
  auto add_strain = [&](double from, double to, double sign, bool ends_step) {
    const double chunk = 0.02;
    const double up = -sign;  // compression (negative strain) raises phi
    for (double t = from + up * chunk; up * (to - t) > 1e-12; t += up * chunk)
      stages.push_back({[&strain, t, sign] { strain(t, sign); }, false});
    stages.push_back({[&strain, to, sign] { strain(to, sign); }, ends_step});
  };
  // 2. compress the gas to phi_0
  for (double t = s.gas.phi + 0.02; s.phi0 - t > 1e-12; t += 0.02)
    stages.push_back({[&compress_gas, t] { compress_gas(t); }, false});
  stages.push_back({[&compress_gas, &s] { compress_gas(s.phi0); }, true});
  stages.push_back({[&] { relax(*sys, s.relax_ratio, s.relax_max); }, true});  // 3. relax
  std::vector<double> sorted = s.targets;
  double from = s.phi0;
  if (s.loading_branch) {  // configurations on the way up (strongly cohesive samples)
    std::sort(sorted.begin(), sorted.end());
    for (double t : sorted)
      add_strain(from, t, -1, false), stages.push_back({save, true}), from = t;
    // No compression to phi_max after the last target: nothing is saved on it, and a
    // strongly cohesive packing that dense can run into the overlap limit.
  } else {
    add_strain(from, s.phi_max, -1, true);      // 4. compress to phi_max
    std::sort(sorted.rbegin(), sorted.rend());  // 5. unload, saving states
    from = s.phi_max;
    for (double t : sorted)
      add_strain(from, t, +1, false), stages.push_back({save, true}), from = t;
  }

  const std::string label = v.tag.empty() ? ck.name : v.tag;  // in log lines
  long first = 0;
  long resumed = -1;  // the stage whose checkpoint the run continued from
  if (ck.resume && std::filesystem::exists(ck.pointer())) {
    std::ifstream in(ck.pointer());
    long k = -1;
    if (!(in >> k) || k < 0)
      throw InputError(ck.pointer() + ": not a stage number; remove the file to start the " +
                       "variant afresh, or run without --resume");
    if (!load_moduli_part(ck.dir, ck.part(k), ck.fingerprint, out))
      throw InputError(ck.pointer() + ": the checkpoint it names is missing; run without --resume");
    resumed = k;
    const long last = static_cast<long>(stages.size()) - 1;
    // A checkpoint at or past the last stage (written by a longer protocol, e.g. one that
    // still compressed on after the last saved configuration) already holds every saved
    // configuration: the preparation is complete.
    first = std::min(k + 1, last + 1);
    for (long q = 0; q < first; ++q) done += stages[q].second ? 1 : 0;
    progress.update(done);
    if (first <= last) {
      if (!std::filesystem::exists(ck.restart(k)))
        throw InputError(ck.pointer() + ": the checkpoint predates exact restarts (no " +
                         ck.restart(k) + "); run without --resume");
      sys.emplace(restart_system<System>(read_config(ck.state(k)), model, s.params));
      sys->load_restart(H5Reader(ck.restart(k)), "/restart");
      std::cerr << "variant " << label << ": continuing after stage " << k + 1 << " of "
                << stages.size() << "\n";
    } else {
      std::cerr << "variant " << label << ": preparation complete in the checkpoint (stage "
                << k + 1 << ")\n";
    }
  }
  // One line per stage: protocol steps last up to hours in a full study, and the progress
  // line only moves when one ends.
  const auto started = std::chrono::steady_clock::now();
  auto log_stage = [&](long k, const Measurements& m) {
    if (!progress.enabled()) return;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    char line[160];
    std::snprintf(line, sizeof line, "variant %s: stage %ld/%zu done, phi %.4f, P %.4g, %.0fs\n",
                  label.c_str(), k + 1, stages.size(), m.phi, m.pressure, seconds);
    std::cerr << line;
  };
  for (long k = first; k < static_cast<long>(stages.size()); ++k) {
    stages[k].first();
    if (stages[k].second) progress.update(++done);
    if (k + 1 == static_cast<long>(stages.size())) break;  // the variant's part follows
    const Measurements m = sys->measure();
    log_stage(k, m);
    write_config(ck.state(k), snapshot(*sys, host.density, m.pressure));
    {
      H5Writer r(ck.restart(k));
      sys->save_restart(r, "/restart");
      r.commit();
    }
    save_moduli_part(ck.dir, ck.part(k), ck.fingerprint, out);
    write_text_file(ck.pointer(), std::to_string(k) + "\n");
    report_progress("variant " + label + ": stage " + std::to_string(k + 1) + " of " +
                    std::to_string(stages.size()) + " checkpointed");
    ck.remove(k - 1);
    if (stop()) return false;
  }
  for (long k = 0; k < static_cast<long>(stages.size()); ++k) ck.remove(k);
  ck.remove(resumed);
  std::filesystem::remove(ck.pointer());
  return true;
}

}  // namespace

void check_elastic_moduli(const SceneFile& scene) { read_setup(scene); }

void run_elastic_moduli(const SceneFile& scene, const RunOptions& opts) {
  const Setup s = read_setup(scene);
  make_directories(opts.out_dir);
  Json summary = Json::object();
  summary["scene"] = "elastic_moduli";
  summary["scene_file"] = scene.path();
  Json& pj = summary["parameters"];
  pj = Json::object();
  for (const auto& [k, v] : scene.used()) pj[k] = Json::raw(v);
  Outputs out;
  // Finished preparation variants are checkpointed here; a fresh run starts without them.
  const std::string parts = opts.out_dir + "/variants";
  const std::string fingerprint = moduli_parameters_fingerprint(scene.used());
  // Never drop hours of preparation silently: a fresh run into a directory that holds
  // checkpoints of an unfinished study is refused.
  if (!opts.resume && std::filesystem::exists(parts) && !std::filesystem::is_empty(parts))
    throw InputError(parts + " holds checkpoints of an unfinished study: continue it with " +
                     "--resume, or remove that directory (or choose another --out) to start over");
  make_directories(parts);

  bool stopped = false;
  with_contact_model(s.contact, [&](const auto& model) {
    using Model = std::decay_t<decltype(model)>;
    if (!s.start_from.empty()) {
      const ConfigState c = read_config(s.start_from);
      std::cerr << "probing the saved configuration " << s.start_from << " (phi " << c.phi << ")\n";
      analyse(s, c, model,
              {{"mu_preparation", kNaN},
               {"seed", kNaN},
               {"ekin_over_epot", kNaN},
               {"inertial_number_preparation", kNaN},
               {"phi_target", kNaN}},
              "", out);
      out.add_config(s.start_from);
      return;
    }
    // Steps: the gas compression, the relaxation, the compression to phi_max (unloading
    // branch only) and one per saved configuration.
    const size_t steps = (s.loading_branch ? 2 : 3) + s.targets.size();
    Progress progress("preparation", static_cast<long>(s.variants.size() * steps), opts.progress);
    long done = 0, prepared = 0, stages_run = 0;
    const auto start = std::chrono::steady_clock::now();
    auto out_of_time = [&] {
      const double minutes =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / 60;
      return opts.stop_after_minutes > 0 && minutes >= opts.stop_after_minutes;
    };
    const std::function<bool()> stop = [&] {
      ++stages_run;
      return (s.stop_after_stages > 0 && stages_run >= s.stop_after_stages) || out_of_time();
    };
    for (const PrepVariant& v : s.variants) {
      const std::string part_name =
          "variant_" + std::to_string(&v - s.variants.data()) + (v.tag.empty() ? "" : "_" + v.tag);
      Outputs part;
      if (opts.resume && load_moduli_part(parts, part_name, fingerprint, part)) {
        std::cerr << "variant " << (v.tag.empty() ? part_name : v.tag)
                  << ": taken from the checkpoint in " << parts << "\n";
        out.append(part);
        progress.update(done += static_cast<long>(steps));
        continue;
      }
      if ((s.stop_after_variants > 0 && prepared == s.stop_after_variants) ||
          (prepared > 0 && out_of_time())) {
        std::cerr << "stopped after " << prepared
                  << " variants (run.stop_after_variants / --stop-after-minutes); continue with "
                     "--resume\n";
        stopped = true;
        return;
      }
      ++prepared;
      const Model prep = std::isnan(v.mu) ? model : with_friction(model, v.mu);
      const double mu = std::isnan(v.mu)
                            ? (s.contact.tangential == "coulomb" ? s.contact.coulomb.mu_s : 0.0)
                            : v.mu;
      const std::string dir = opts.out_dir + "/configs" + (v.tag.empty() ? "" : "/" + v.tag);
      make_directories(dir);
      std::vector<double> targets = s.targets;
      const StageCheckpoints ck{parts, part_name, fingerprint, opts.resume};
      const bool finished = prepare(s, v, prep, part, progress, done, ck, stop,
                                    [&](const ConfigState& c, double ratio, double I) {
                                      // The target this configuration was saved at (the closest
                                      // listed value).
                                      double target = targets[0];
                                      for (double t : targets)
                                        if (std::fabs(t - c.phi) < std::fabs(target - c.phi))
                                          target = t;
                                      char name[64];
                                      std::snprintf(name, sizeof name, "/phi_%.4f.h5", target);
                                      write_config(dir + name, c);
                                      part.add_config(dir + name);
                                      analyse(s, c, prep,
                                              {{"mu_preparation", mu},
                                               {"seed", static_cast<double>(v.seed)},
                                               {"ekin_over_epot", ratio},
                                               {"inertial_number_preparation", I},
                                               {"phi_target", target}},
                                              v.tag, part);
                                    });
      if (!finished) {
        std::cerr << "stopped at a checkpoint (run.stop_after_stages / --stop-after-minutes); "
                     "continue with --resume\n";
        stopped = true;
        return;
      }
      save_moduli_part(parts, part_name, fingerprint, part);
      out.append(part);
    }
  });

  if (stopped) return;  // the checkpoints in variants/ are the output so far
  H5Writer h5(opts.out_dir + "/results.h5");
  for (const auto& [k, v] : out.table) h5.write("/table/" + k, v);
  for (const auto& [k, v] : out.prep) h5.write("/preparation/" + k, v);
  for (const auto& [k, v] : out.sweep_data) h5.write(k, v);
  h5.commit();
  summary["configurations"] = out.configs;
  summary["table"] = out.rows;
  if (!s.amplitudes.empty()) summary["amplitude_sweeps"] = out.sweeps;
  if (s.halving) {
    // Largest relative change of K, G, M over all configurations when the probing
    // amplitude or rate is halved: the elastic-plateau criterion is < 1 %.
    // Configurations below jamming have no elastic plateau.
    double worst_a = 0, worst_r = 0;
    const auto& jammed = out.table.at("jammed");
    for (const char* m : {"K", "G", "M"}) {
      const auto& a = out.table.at(std::string("halving_amplitude_rel_change_") + m);
      const auto& r = out.table.at(std::string("halving_rate_rel_change_") + m);
      for (size_t i = 0; i < jammed.size(); ++i)
        if (jammed[i] > 0) worst_a = std::max(worst_a, a[i]), worst_r = std::max(worst_r, r[i]);
    }
    Json& hc = summary["halving_check"];
    hc = Json::object();
    hc["max_rel_change_half_amplitude"] = worst_a;
    hc["max_rel_change_half_rate"] = worst_r;
    hc["within_1_percent"] = worst_a < 0.01 && worst_r < 0.01;
    hc["unjammed_configurations_left_out"] =
        static_cast<double>(std::count(jammed.begin(), jammed.end(), 0.0));
  }
  // Scatter of the moduli over seeds at each size and target (system-size study).
  const std::vector<SizeScatter> scatter = size_scatter(out.table);
  if (!scatter.empty()) {
    bool several_mu = false;
    const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
    for (const SizeScatter& e : scatter) several_mu = several_mu || !same(e.mu, scatter[0].mu);
    Json sc = Json::array();
    for (const SizeScatter& e : scatter) {
      Json j = Json::object();
      if (several_mu) j["mu_preparation"] = e.mu;
      j["particles"] = e.particles, j["phi_target"] = e.phi_target;
      j["samples"] = static_cast<double>(e.samples);
      j["K_star_mean"] = e.K_mean, j["K_star_std"] = e.K_std;
      j["G_star_mean"] = e.G_mean, j["G_star_std"] = e.G_std;
      sc.push(j);
    }
    summary["size_scatter"] = sc;
  }
  write_text_file(opts.out_dir + "/summary.json", summary.dump());
  std::filesystem::remove_all(parts);  // everything is in results.h5 and summary.json now
  if (opts.charts) run_plot_script("elastic_moduli.py", opts.out_dir + "/results.h5", opts.out_dir);
}

}  // namespace granular
