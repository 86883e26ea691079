// Scene `elastic_moduli`: the preparation protocol of docs/model_dem.md §6 (gas -> compress to
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

#include "core/io/output.hpp"
#include "core/run/ensemble.hpp"
#include "core/run/finite.hpp"
#include "core/run/progress.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/contact_config.hpp"
#include "scenarios/common/element_test.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/moduli/jamming_point.hpp"
#include "scenarios/moduli/moduli_outputs.hpp"
#include "scenarios/moduli/moduli_preparation.hpp"
#include "scenarios/moduli/moduli_probing.hpp"
#include "scenarios/moduli/moduli_setup.hpp"
#include "scenarios/moduli/moduli_theory.hpp"
#include "scenarios/moduli/study_units.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

using namespace moduli_study;

void check_elastic_moduli(const SceneFile& scene) { read_setup(scene); }

namespace {
// The contact law a variant is prepared with: its own friction and cohesion where it lists
// them.
template <class Model>
Model preparation_model(const Model& model, const PrepVariant& v) {
  Model prep = std::isnan(v.mu) ? model : with_friction(model, v.mu);
  if (!std::isnan(v.kc)) prep = with_cohesion(prep, v.kc);
  return prep;
}

// The units of the study's columns (analyse in moduli_probing.hpp, prepare in
// moduli_preparation.hpp), in the engine's units (mm, us, ug). The "_star" moduli and
// pressures are divided by each configuration's scale k_n / dbar (k_n: kn_mean; P / k1_star
// by k1 / dbar), the theories give the same dimensionless moduli, and strains, inertial
// numbers, fractions, fluctuations (eta), fabric and relative changes are pure numbers.
ModuliUnits elastic_moduli_units() {
  ModuliUnits u;
  for (const char* k : {"mu_preparation",
                        "seed",
                        "ekin_over_epot",
                        "inertial_number_preparation",
                        "phi_target",
                        "particles",
                        "jammed",
                        "phi",
                        "z_corrected",
                        "chi",
                        "rattler_fraction",
                        "pressure_star",
                        "kt_kn",
                        "inertial_number_probe",
                        "probe_strain_steps",
                        "K_star",
                        "G_star",
                        "M_star",
                        "K_n_star",
                        "K_t_star",
                        "G_n_star",
                        "G_t_star",
                        "M_over_K_plus_4G_3",
                        "isotropic_reversal_residual",
                        "eta_K",
                        "eta_G",
                        "eta_M",
                        "eta_K_per_contact",
                        "eta_K_normal",
                        "normal_relaxation_K",
                        "halving_amplitude_rel_change_K",
                        "halving_amplitude_rel_change_G",
                        "halving_amplitude_rel_change_M",
                        "halving_rate_rel_change_K",
                        "halving_rate_rel_change_G",
                        "halving_rate_rel_change_M",
                        "K_emt",
                        "G_emt",
                        "K_ft1",
                        "G_ft1",
                        "K_ft2",
                        "G_ft2",
                        "K_ft2_closure",
                        "G_ft2_closure",
                        "rho",
                        "rho_s",
                        "zeta",
                        "fabric_xx",
                        "fabric_yy",
                        "fabric_zz",
                        "fabric_xy",
                        "fabric_xz",
                        "fabric_yz",
                        "pressure_over_k1_star",
                        "pressure_normal_star",
                        "pressure_tangential_star"})
    u.table[k] = "1";
  u.table["kn_mean"] = "N mm-1";         // mean normal contact stiffness
  u.table["kc_preparation"] = "N mm-1";  // adhesive stiffness k_c
  for (const char* k : {"phi", "z_corrected", "inertial_number", "variant", "direction",
                        "pressure_star", "ekin_over_epot"})
    u.prep[k] = "1";
  u.prep["pressure"] = "MPa";
  u.prep["volumetric_strain_rate"] = "us-1";
  for (int q = 0; q < 7; ++q) {
    const std::string k = "contact_fraction_" + std::to_string(q) + (q == 6 ? "_or_more" : "");
    u.table[k] = u.prep[k] = "1";
  }
  // Amplitude sweeps (/sweep/...) and reversibility tests (/reversibility/...): strains,
  // dimensionless moduli, counts and ratios.
  for (const char* k :
       {"amplitude", "K_star", "G_star", "M_star", "eta_K", "eta_G", "eta_M", "inertial_number",
        "strain_steps", "reversal_residual", "fabric_v_change_K", "fabric_v_change_G",
        "fabric_dev_change_G", "prestrain", "mode", "loading_modulus_star",
        "unloading_modulus_star", "residual", "relaxed_ekin_over_epot"})
    u.sweep[k] = "1";
  return u;
}

// In check mode, builds each variant's first systems as prepare() builds them (a saved
// configuration is probed as it is), so that the run's guards apply to `granular check`.
void check_variants(const SceneFile& scene, const RunOptions& opts, const Setup& s) {
  check_first_system(scene, opts, [&] {
    if (!s.start_from.empty()) return;
    with_contact_model(s.contact, [&](const auto& model) {
      using System = DemSystem<Exec, std::decay_t<decltype(model)>>;
      for (const PrepVariant& v : s.variants) {
        const Setup sv = for_variant(s, v);
        GasSpec gas = sv.gas;
        gas.count = v.count, gas.seed = v.seed;
        PeriodicBox box;
        const HostParticles host = random_gas(gas, box);
        const auto prep = preparation_model(model, v);
        System(Particles<Exec>::from_host(host), box, prep, sv.params);
        if (sv.friction_from_phi0)
          System(Particles<Exec>::from_host(host), box, with_friction(prep, 0.0), sv.params);
      }
    });
  });
}

// Probes the packing or saved configuration of [start] from: one configuration, which rank 0
// probes (the other ranks return no outputs).
template <class Model>
Outputs probe_start(const Setup& s, const Model& model) {
  const ConfigState c = s.start_packing ? *s.start_packing : read_config(s.start_from);
  std::cerr << "probing the " << (s.start_packing ? "packing " : "saved configuration ")
            << s.start_from << " (phi " << c.phi << ")\n";
  Outputs out;
  if (!ensemble::root()) return out;
  ConfigResults r = analyse(s, c, model,
                            {{"mu_preparation", kNaN},
                             {"seed", kNaN},
                             {"ekin_over_epot", kNaN},
                             {"inertial_number_preparation", kNaN},
                             {"phi_target", kNaN}},
                            "");
  r.config = s.start_from;
  out.add(r);
  return out;
}

// The checkpoint parts of a study: their folder, the fingerprint of the parameters they were
// made with, one name per variant, and which variants are done or this rank's.
struct StudyParts {
  std::string parts, fingerprint;
  std::vector<std::string> names;
  StudyDeal deal;
};

// The study's checkpoint folder, opened (a fresh run refuses one of an unfinished study), its
// parts named, and the variants dealt over the ranks.
StudyParts open_study(const SceneFile& scene, const RunOptions& opts, const Setup& s) {
  // Finished preparation variants are checkpointed here; a fresh run starts without them.
  StudyParts study;
  study.parts = open_study_checkpoints(opts.out_dir, opts.resume);
  study.fingerprint = moduli_parameters_fingerprint(scene.used());
  for (const PrepVariant& v : s.variants)
    study.names.push_back("variant_" + std::to_string(&v - s.variants.data()) +
                          (v.tag.empty() ? "" : "_" + v.tag));
  if (s.start_from.empty())
    study.deal = deal_study_units(study.parts, study.names, study.fingerprint, opts.resume);
  return study;
}

// When a run stops at a checkpoint: after run.stop_after_variants variants or
// run.stop_after_stages stages, or once --stop-after-minutes have passed.
class StopRules {
 public:
  StopRules(const Setup& s, const RunOptions& opts)
      : s_(s), opts_(opts), start_(std::chrono::steady_clock::now()) {}
  bool out_of_time() const {
    const double minutes =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count() / 60;
    return opts_.stop_after_minutes > 0 && minutes >= opts_.stop_after_minutes;
  }
  // Before the next variant, `prepared` having been prepared by this run.
  bool before_variant(long prepared) const {
    return (s_.stop_after_variants > 0 && prepared == s_.stop_after_variants) ||
           (prepared > 0 && out_of_time());
  }
  // After a checkpointed stage.
  bool after_stage() {
    ++stages_run_;
    return (s_.stop_after_stages > 0 && stages_run_ >= s_.stop_after_stages) || out_of_time();
  }

 private:
  const Setup& s_;
  const RunOptions& opts_;
  std::chrono::steady_clock::time_point start_;
  long stages_run_ = 0;
};

// The target a configuration was saved at (the closest listed value).
double saved_target(const std::vector<double>& targets, double phi) {
  double target = targets[0];
  for (double t : targets)
    if (std::fabs(t - phi) < std::fabs(target - phi)) target = t;
  return target;
}

// The columns of a variant's rows that describe its preparation (the configuration's
// E_kin/E_pot, inertial number and target are added as each is saved).
std::map<std::string, double> preparation_context(const Setup& s, const PrepVariant& v) {
  const double kc =
      std::isnan(v.kc) ? (s.contact.normal == "hysteretic" ? s.contact.hysteretic.kc : 0.0) : v.kc;
  const double mu =
      std::isnan(v.mu) ? (s.contact.tangential == "coulomb" ? s.contact.coulomb.mu_s : 0.0) : v.mu;
  return {{"mu_preparation", mu}, {"kc_preparation", kc}, {"seed", static_cast<double>(v.seed)}};
}

// Prepares and probes one variant: each relaxed configuration is written to configs/ and
// probed as the preparation saves it. Checkpointed in the study's parts as it goes.
template <class Model>
Prepared run_variant(const Setup& s, const Model& model, const RunOptions& opts,
                     const StudyParts& study, size_t unit, Progress& progress, long& done,
                     const std::function<bool()>& stop) {
  const PrepVariant& v = s.variants[unit];
  const Model prep = preparation_model(model, v);
  const std::map<std::string, double> context = preparation_context(s, v);
  const std::string dir = opts.out_dir + "/configs" + (v.tag.empty() ? "" : "/" + v.tag);
  make_directories(dir);
  const StageCheckpoints ck{study.parts, study.names[unit], study.fingerprint, opts.resume};
  const Setup sv = for_variant(s, v);
  return prepare(sv, unit, prep, progress, done, ck, stop,
                 [&](const ConfigState& c, double ratio, double I) {
                   const double target = saved_target(s.targets, c.phi);
                   char name[64];
                   std::snprintf(name, sizeof name, "/phi_%.4f.h5", target);
                   write_config(dir + name, c);
                   std::map<std::string, double> row = context;
                   row["ekin_over_epot"] = ratio, row["inertial_number_preparation"] = I;
                   row["phi_target"] = target;
                   ConfigResults r = analyse(sv, c, prep, row, v.tag);
                   r.config = dir + name;
                   return r;
                 });
}

// What a study's variants returned: each one's outputs in variant order (those a resumed run
// took from their checkpoints included; over several ranks none, rank 0 reads every part
// back), the parts this rank ran and the configurations it wrote, and whether it stopped
// part-way (a stage or variant budget, --stop-after-minutes: the checkpoints are its output
// so far).
struct VariantsRun {
  std::vector<Outputs> parts;
  std::vector<std::string> ran, configs_written;
  bool stopped = false;
};

// Prepares and probes this rank's variants, each saved as a checkpoint part; those a resumed
// run finds done are taken from their parts.
template <class Model>
VariantsRun run_variants(const Setup& s, const Model& model, const RunOptions& opts,
                         const StudyParts& study) {
  const bool spread = ensemble::size() > 1;
  // Steps: the gas compression, the relaxation, the compression to phi_max (unloading
  // branch only) and one per saved configuration.
  const size_t steps = (s.loading_branch ? 2 : 3) + s.targets.size();
  size_t units_here = 0;  // this rank's variants and those taken from checkpoints
  for (size_t k = 0; k < s.variants.size(); ++k)
    units_here += study.deal.done[k] || study.deal.mine(k);
  Progress progress("preparation", static_cast<long>(units_here * steps), opts.progress);
  long done = 0, prepared = 0;
  StopRules rules(s, opts);
  const std::function<bool()> stop = [&] { return rules.after_stage(); };
  VariantsRun run;
  for (size_t unit = 0; unit < s.variants.size(); ++unit) {
    const std::string& part_name = study.names[unit];
    if (study.deal.done[unit]) {
      const std::string& tag = s.variants[unit].tag;
      std::cerr << ensemble::prefix() << "variant " << (tag.empty() ? part_name : tag)
                << ": taken from the checkpoint in " << study.parts << "\n";
      Outputs part;
      if (!spread && load_moduli_part(study.parts, part_name, study.fingerprint, part))
        run.parts.push_back(std::move(part));
      progress.update(done += static_cast<long>(steps));
      continue;
    }
    if (!study.deal.mine(unit)) continue;
    if (rules.before_variant(prepared)) {
      std::cerr << "stopped after " << prepared
                << " variants (run.stop_after_variants / --stop-after-minutes); continue with "
                   "--resume\n";
      run.stopped = true;
      return run;
    }
    ++prepared;
    Prepared p = run_variant(s, model, opts, study, unit, progress, done, stop);
    run.ran.push_back(part_name);
    run.configs_written.insert(run.configs_written.end(), p.out.config_paths.begin(),
                               p.out.config_paths.end());
    if (!p.finished) {
      std::cerr << "stopped at a checkpoint (run.stop_after_stages / --stop-after-minutes); "
                   "continue with --resume\n";
      run.stopped = true;
      return run;
    }
    if (!spread) run.parts.push_back(std::move(p.out));  // prepare() saved it as a checkpoint
  }
  return run;
}

// The largest relative change of K, G, M over the jammed configurations when the probing
// amplitude or rate is halved, and how many unjammed ones were left out.
struct HalvingCheck {
  double worst_amplitude = 0, worst_rate = 0, unjammed = 0;
};

// The study's results: every variant's outputs in variant order, and what summary.json
// derives from them.
struct StudyResults {
  Outputs out;
  std::vector<JammingPoint> jamming;  // per variant, on the unloading branch
  std::optional<HalvingCheck> halving;
  std::vector<SizeScatter> scatter;
};

// Largest relative change of K, G, M over all configurations when the probing amplitude or
// rate is halved: the elastic-plateau criterion is < 1 %. Configurations below jamming have
// no elastic plateau.
HalvingCheck worst_halving(const Outputs& out) {
  HalvingCheck h;
  const auto& jammed = out.table.at("jammed");
  for (const char* m : {"K", "G", "M"}) {
    const auto& a = out.table.at(std::string("halving_amplitude_rel_change_") + m);
    const auto& r = out.table.at(std::string("halving_rate_rel_change_") + m);
    for (size_t i = 0; i < jammed.size(); ++i)
      if (jammed[i] > 0)  // a NaN change is kept: it fails the check and stops the summary
        h.worst_amplitude = max_keep_nan(h.worst_amplitude, a[i]),
        h.worst_rate = max_keep_nan(h.worst_rate, r[i]);
  }
  h.unjammed = static_cast<double>(std::count(jammed.begin(), jammed.end(), 0.0));
  return h;
}

// The study's outputs and what follows from them: the jamming density per preparation
// variant from its unloading series, the halving check and the scatter over seeds.
StudyResults study_results(const Setup& s, Outputs out) {
  StudyResults r;
  r.out = std::move(out);
  if (!s.loading_branch) {
    const bool hertz = s.contact.normal == "hertz";
    r.jamming = jamming_points(r.out.prep, hertz ? "pressure" : "pressure_star", hertz ? 1.5 : 1.0,
                               s.jamming_p_max > 0 ? s.jamming_p_max : -1);
  }
  if (s.halving) r.halving = worst_halving(r.out);
  r.scatter = size_scatter(r.out.table);
  return r;
}

// Runs the study: the [start] configuration, or this rank's variants. On rank 0 its results
// in variant order; nothing on the other ranks, or where the study stopped at a checkpoint
// (the checkpoints in variants/ are the output so far).
std::optional<StudyResults> run_study(const Setup& s, const RunOptions& opts,
                                      const StudyParts& study) {
  Outputs out;
  VariantsRun run;
  with_contact_model(s.contact, [&](const auto& model) {
    if (!s.start_from.empty())
      out = probe_start(s, model);
    else
      run = run_variants(s, model, opts, study);
  });
  // Over several ranks each runs its share of the variants and rank 0 reads every part back
  // in variant order; one rank runs them all, in order, as parts of a single process.
  if (ensemble::size() > 1 && s.start_from.empty())
    run.stopped = gather_study_units(study.parts, study.names, run.ran, run.configs_written,
                                     study.fingerprint, run.stopped, out);
  else
    for (const Outputs& part : run.parts) out.append(part);
  if (!ensemble::root() || run.stopped) return std::nullopt;
  return study_results(s, std::move(out));
}

// Jamming density per preparation variant from its unloading series.
Json jamming_json(const Setup& s, const std::vector<JammingPoint>& points) {
  Json jam = Json::array();
  for (const JammingPoint& j : points) {
    Json e = Json::object();
    const PrepVariant& v = s.variants.at(j.variant);
    e["variant"] = j.variant;
    if (!v.tag.empty()) e["tag"] = v.tag;
    e["mu_preparation"] = std::isnan(v.mu) ? Json() : Json(v.mu);
    if (!std::isnan(v.kc)) e["kc_preparation"] = v.kc;
    if (!std::isnan(v.dt)) e["dt"] = v.dt;
    e["particles"] = v.count;
    e["fit_points"] = j.points;
    e["phi_J"] = std::isnan(j.phi_j) ? Json() : Json(j.phi_j);
    e["phi_J_stderr"] = std::isnan(j.phi_j_stderr) ? Json() : Json(j.phi_j_stderr);
    e["phi_lowest_jammed"] = std::isnan(j.phi_lowest_jammed) ? Json() : Json(j.phi_lowest_jammed);
    e["phi_highest_unjammed"] =
        std::isnan(j.phi_highest_unjammed) ? Json() : Json(j.phi_highest_unjammed);
    jam.push(e);
  }
  return jam;
}

// The halving check of summary.json.
Json halving_json(const HalvingCheck& h) {
  Json hc = Json::object();
  hc["max_rel_change_half_amplitude"] = h.worst_amplitude;
  hc["max_rel_change_half_rate"] = h.worst_rate;
  hc["within_1_percent"] = h.worst_amplitude < 0.01 && h.worst_rate < 0.01;
  hc["unjammed_configurations_left_out"] = h.unjammed;
  return hc;
}

// Scatter of the moduli over seeds at each size and target (system-size study).
Json size_scatter_json(const std::vector<SizeScatter>& scatter) {
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
  return sc;
}

// What the study adds to summary.json after its results.
void write_study_summary(const Setup& s, const StudyResults& r, Json& summary) {
  const Outputs& out = r.out;
  summary["configurations"] = out.configs;
  // The configurations are large restartable files the run regenerates; a summary kept as a
  // reference output travels without them, and says so.
  summary["configurations_note"] =
      "relaxed configurations written by this run under its output directory (configs/); "
      "they are not part of committed reference outputs: the same command regenerates them";
  summary["table"] = out.rows;
  bool own_steps = false;
  for (const PrepVariant& v : s.variants) own_steps = own_steps || !std::isnan(v.dt);
  if (own_steps)
    summary["time_step_note"] =
        "each k_c variant ran with its own time step (preparation.dt, listed with the variant "
        "under jamming): the one its stiffest spring allows; every step count of the protocol "
        "(probe strain and relaxation, the relaxation cap) was rescaled to span the same "
        "physical time as with run.dt, so the rates and durations are the same for all";
  if (!s.loading_branch) {
    summary["jamming"] = jamming_json(s, r.jamming);
    summary["jamming_note"] =
        "phi_J: root of the straight line P^(1/alpha) against phi (alpha = 1 linear, 3/2 Hertz) "
        "fitted to the unloading samples with 0 < P <= preparation.jamming_fit_pressure_max; "
        "phi_lowest_jammed / phi_highest_unjammed: the lowest density of the unloading branch "
        "that still has a contact network and the highest that has none (they overlap where "
        "the network flickers near jamming; bounded by the lowest target)";
  }
  // Amplitude sweeps and reversibility tests, one entry per configuration (the columns say
  // which: "amplitude" or "prestrain").
  if (!s.amplitudes.empty() || !s.prestrains.empty()) summary["amplitude_sweeps"] = out.sweeps;
  if (r.halving) summary["halving_check"] = halving_json(*r.halving);
  if (!r.scatter.empty()) summary["size_scatter"] = size_scatter_json(r.scatter);
}

// Writes the study: results.h5 (the table, preparation series and sweeps), then summary.json
// and the charts.
void write_study(SceneOutput& output, const Setup& s, const StudyResults& r) {
  r.out.write_results(output.h5(), elastic_moduli_units());
  write_study_summary(s, r, output.summary());
  output.finish({"table"});
}

}  // namespace

void run_elastic_moduli(const SceneFile& scene, const RunOptions& opts) {
  const Setup s = read_setup(scene);
  check_variants(scene, opts, s);
  if (s.start_from.empty()) require_checkpoint_to_resume(opts, study_checkpoints(opts.out_dir));
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "elastic_moduli");
  output.summary();  // lists the keys read so far
  const StudyParts study = open_study(scene, opts, s);
  const std::optional<StudyResults> results = run_study(s, opts, study);
  if (!results) return;  // the checkpoints in variants/ are the output so far
  write_study(output, s, *results);
  remove_study_checkpoints(study.parts);  // everything is in results.h5 and summary.json now
}

}  // namespace granular
