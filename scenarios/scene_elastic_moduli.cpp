// Scene `elastic_moduli`: the preparation protocol of dem.md section 6 (gas -> compress to
// phi_0 -> relax -> compress to phi_max -> decompress), configurations saved on the
// unloading branch at the listed volume fractions and relaxed, then elastic probing of
// each (sliding switched off unless the scene keeps friction): K*, G*, M* against phi Z
// next to effective-medium and fluctuation theory, in a table, a chart and summary.json.
#include <Kokkos_Core.hpp>
#include <cmath>
#include <iostream>
#include <limits>

#include "core/output.hpp"
#include "core/progress.hpp"
#include "scenarios/contact_config.hpp"
#include "scenarios/dem_output.hpp"
#include "scenarios/element_test.hpp"
#include "scenarios/moduli_theory.hpp"
#include "scenarios/packing.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {
using Exec = Kokkos::DefaultExecutionSpace;

// The same contact model with infinite friction: elastic probing must not slide.
template <class Model>
Model without_sliding(Model m) {
  if constexpr (Model::tangential_type::active) {
    const double inf = std::numeric_limits<double>::infinity();
    for (auto& row : m.tangential.table.p)
      for (auto& q : row) q.mu_s = q.mu_d = inf;
  }
  return m;
}
}  // namespace

void run_elastic_moduli(const SceneFile& scene, const RunOptions& opts) {
  GasSpec gas;
  gas.count = static_cast<int>(scene.integer("particles.count"));
  gas.diameter_min = scene.real("particles.diameter_min");
  gas.diameter_max = scene.real("particles.diameter_max");
  gas.density = scene.real("particles.density");
  gas.seed = static_cast<std::uint64_t>(scene.integer("particles.seed", 1));
  gas.speed = scene.real("particles.initial_speed", 0.0);
  gas.phi = scene.real("preparation.phi_gas", 0.3);
  const ContactConfig contact = ContactConfig::read(scene);
  DemParams params;
  params.dt = scene.real("run.dt");
  params.skin = scene.real("run.skin");
  params.damping.translational = scene.real("damping.background", 0.0);
  params.damping.rotational = scene.real("damping.rotational", 0.0);
  params.rattler_threshold = static_cast<int>(scene.integer("run.rattler_threshold", 3));
  params.max_overlap = scene.real("run.max_overlap", 0.5);
  const double phi0 = scene.real("preparation.phi_0", 0.5);
  const double phi_max = scene.real("preparation.phi_max");
  const double rate = scene.real("preparation.volumetric_strain_rate");
  const auto targets = scene.reals("preparation.unloading_targets");
  const double relax_ratio = scene.real("preparation.relax_ratio", 1e-8);
  const long relax_max = scene.integer("preparation.relax_max_steps", 200000);
  const double amplitude = scene.real("probe.amplitude", 3e-6);
  const long strain_steps = scene.integer("probe.strain_steps", 2000);
  const long probe_relax = scene.integer("probe.relax_steps", 2000);
  const bool keep_friction = scene.flag("probe.keep_friction", false);
  scene.require(phi0 > gas.phi && phi_max > phi0 && phi_max < 1, "preparation.phi_max",
                "must satisfy phi_gas < phi_0 < phi_max < 1");
  for (double t : targets)
    scene.require(t > phi0 && t < phi_max, "preparation.unloading_targets",
                  "must lie between phi_0 and phi_max");
  scene.require(rate > 0, "preparation.volumetric_strain_rate", "must be positive");
  scene.require(amplitude > 0 && amplitude < 1e-2, "probe.amplitude", "must be in (0, 1e-2)");
  scene.reject_unknown_keys();
  make_directories(opts.out_dir);

  const double axis_rate = rate / 3;
  PeriodicBox box;
  const HostParticles host = random_gas(gas, box);
  // Size moment D = <d^2>/<d^3> * dbar for the theories.
  double s1 = 0, s2 = 0, s3 = 0;
  for (double a : host.radius) s1 += 2 * a, s2 += 4 * a * a, s3 += 8 * a * a * a;
  const double dbar = s1 / host.size(), D = s2 / s3 * dbar;
  const double kn_ref = contact.normal == "linear"       ? contact.linear.kn
                        : contact.normal == "hysteretic" ? contact.hysteretic.k2
                                                         : 0.0;
  const double kt_kn = contact.tangential == "coulomb" && contact.coulomb.law == 0 && kn_ref > 0
                           ? contact.coulomb.kt / kn_ref
                           : 0.0;

  Json summary = Json::object();
  summary["scene"] = "elastic_moduli";
  summary["scene_file"] = scene.path();
  Json& pj = summary["parameters"];
  pj = Json::object();
  for (const auto& [k, v] : scene.used()) pj[k] = Json::raw(v);
  Json rows = Json::array();
  H5Writer h5(opts.out_dir + "/results.h5");
  std::map<std::string, std::vector<double>> table;

  with_contact_model(contact, [&](const auto& model) {
    using Model = std::decay_t<decltype(model)>;
    DemSystem<Exec, Model> sys(Particles<Exec>::from_host(host), box, model, params);
    std::vector<double> prep_phi, prep_p, prep_z;
    auto sample = [&](const Measurements& m) {
      prep_phi.push_back(m.phi), prep_p.push_back(m.pressure), prep_z.push_back(m.z_corrected);
    };
    Progress progress("preparation", 4 + static_cast<long>(targets.size()), opts.progress);
    strain_to_phi(sys, phi0, -axis_rate, 500, sample);  // 2. compress to phi_0
    progress.update(1);
    relax(sys, relax_ratio, relax_max);  // 3. relax
    progress.update(2);
    strain_to_phi(sys, phi_max, -axis_rate, 500, sample);  // 4. compress to phi_max
    progress.update(3);
    std::vector<double> sorted = targets;
    std::sort(sorted.rbegin(), sorted.rend());  // 5. unload, saving states
    long done = 3;
    for (double t : sorted) {
      strain_to_phi(sys, t, axis_rate, 500, sample);
      const double ratio = relax(sys, relax_ratio, relax_max);
      const Measurements m = sys.measure();
      const std::string g = "/configurations/phi_" + std::to_string(t);
      write_state(h5, g, sys.particles(), sys.box(), gas.density);
      // Probe in place (history kept), with sliding off unless the scene keeps friction;
      // the unloading continues afterwards with the preparation friction.
      if (!keep_friction) sys.set_model(without_sliding(model));
      double reversal = 0;
      const Moduli mod = probe_moduli(sys, amplitude, strain_steps, probe_relax, &reversal);
      sys.set_model(model);
      TheoryInput ti;
      ti.phi = m.phi, ti.z = m.z_corrected, ti.chi = m.chi, ti.kt_kn = kt_kn, ti.D = D;
      const TheoryResult th = moduli_theory(ti);
      ti.chi = -1;
      const TheoryResult thc = moduli_theory(ti);
      const double scale = kn_ref > 0 ? dbar / kn_ref : 1.0;
      const std::map<std::string, double> row = {
          {"phi", m.phi},
          {"z_corrected", m.z_corrected},
          {"chi", m.chi},
          {"rattler_fraction", m.rattlers / host.size()},
          {"pressure_star", m.pressure * scale},
          {"ekin_over_epot", ratio},
          {"K_star", mod.K * scale},
          {"G_star", mod.G * scale},
          {"M_star", mod.M * scale},
          {"K_n_star", mod.K_n * scale},
          {"K_t_star", mod.K_t * scale},
          {"G_n_star", mod.G_n * scale},
          {"G_t_star", mod.G_t * scale},
          {"M_over_K_plus_4G_3", mod.M / (mod.K + 4 * mod.G / 3)},
          {"isotropic_reversal_residual", reversal},
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
      Json r = Json::object();
      for (const auto& [k, v] : row) r[k] = v, table[k].push_back(v);
      rows.push(r);
      std::cerr << "phi " << m.phi << ": Z " << m.z_corrected << "  K* " << mod.K * scale << "  G* "
                << mod.G * scale << "  M/(K+4G/3) " << mod.M / (mod.K + 4 * mod.G / 3) << "\n";
      progress.update(++done);
    }
    h5.write("/preparation/phi", prep_phi);
    h5.write("/preparation/pressure", prep_p);
    h5.write("/preparation/z_corrected", prep_z);
  });
  for (const auto& [k, v] : table) h5.write("/table/" + k, v);
  h5.attribute("/", "D", D);
  h5.attribute("/", "kt_kn", kt_kn);
  h5.commit();
  summary["size_moment_D"] = D;
  summary["table"] = rows;
  write_text_file(opts.out_dir + "/summary.json", summary.dump());
  if (opts.charts) run_plot_script("elastic_moduli.py", opts.out_dir + "/results.h5", opts.out_dir);
}

}  // namespace granular
