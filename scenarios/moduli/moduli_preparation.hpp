// The elastic_moduli preparation protocol (docs/model_dem.md §6) for one variant, cut into
// stages that are checkpointed exactly, so that a study can stop at any stage and resume
// bit for bit.
#pragma once
#include <filesystem>
#include <functional>
#include <string>

#include "core/run/progress.hpp"
#include "scenarios/common/restart_file.hpp"
#include "scenarios/common/run_report.hpp"
#include "scenarios/moduli/moduli_outputs.hpp"
#include "scenarios/moduli/moduli_probing.hpp"

namespace granular::moduli_study {

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
  // The system's exact state after stage k (write_restart, scenarios/common/restart_file.hpp).
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
// Returns false when `stop` asked to end the run at a checkpoint. `variant` indexes
// s.variants: the preparation series are labelled with it (the jamming fit groups by it).
template <class Model>
bool prepare(const Setup& s, size_t variant, const Model& model, Outputs& out, Progress& progress,
             long& done, const StageCheckpoints& ck, const std::function<bool()>& stop,
             const std::function<void(const ConfigState&, double, double)>& on_config) {
  const PrepVariant& v = s.variants.at(variant);
  GasSpec gas = s.gas;
  gas.count = v.count, gas.seed = v.seed;
  PeriodicBox box;
  const HostParticles host = random_gas(gas, box);
  double dsum = 0;
  for (double a : host.radius) dsum += 2 * a;
  const double dbar = dsum / host.size();
  using System = DemSystem<Exec, Model>;
  std::optional<System> sys;
  // With preparation.friction_from = "phi_0" the gas is compressed and relaxed without
  // friction and the preparation friction acts from the compression to phi_max on.
  const Model gas_model = s.friction_from_phi0 ? with_friction(model, 0.0) : model;
  sys.emplace(Particles<Exec>::from_host(host), box, gas_model, s.params);
  double rate_now = s.rate;
  double direction_now = 1;  // +1 compression, -1 decompression (the unloading branch)
  // P* = P dbar / k_n where k_n is a constant of the law (linear; hysteretic: k_2); a Hertz
  // stiffness depends on the overlaps, so its series keeps P only (P* is NaN).
  const double kn_fixed = s.contact.normal == "linear"       ? s.contact.linear.kn
                          : s.contact.normal == "hysteretic" ? s.contact.hysteretic.k2
                                                             : kNaN;
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
    out.prep["variant"].push_back(static_cast<double>(variant));
    out.prep["direction"].push_back(direction_now);
    out.prep["pressure_star"].push_back(m.pressure * dbar / kn_fixed);
    out.prep["ekin_over_epot"].push_back(m.epot > 0 ? m.ekin / m.epot : kNaN);
    for (int k = 0; k < 7; ++k)
      out.prep[k < 6 ? "contact_fraction_" + std::to_string(k) : "contact_fraction_6_or_more"]
          .push_back(m.contact_histogram[k]);
  };
  auto strain = [&](double target, double sign) {
    rate_now = s.rate;      // what the recorded series and I report (rate_of lowers it if adaptive)
    direction_now = -sign;  // a negative strain compresses
    std::function<double(const Measurements&)> f = nullptr;
    if (s.prep_inertial > 0) f = [&, sign](const Measurements& m) { return sign * rate_of(m) / 3; };
    strain_to_phi(*sys, target, sign * s.rate / 3, 500, sample, f);
  };
  auto compress_gas = [&](double target) {
    rate_now = s.gas_rate;
    direction_now = 1;
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
  stages.push_back({[&] {
                      relax(*sys, s.relax_ratio, s.relax_max);
                      sys->set_model(model);  // friction from here on (a no-op by default)
                    },
                    true});  // 3. relax
  const long relaxed_stage = static_cast<long>(stages.size()) - 1;
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
      // The saved state alone makes the system (no build nor force pass first).
      const H5Reader restart(ck.restart(k));
      try {
        sys.emplace(read_restart<System>(restart, "/restart"),
                    k < relaxed_stage ? gas_model : model, s.params, restart_origin("/restart"));
      } catch (const InputError& e) {
        throw InputError("--resume: " + ck.restart(k) + ": " + e.what() + "; run without --resume");
      }
      // The protocol's own state: the rate and direction the next stage starts from (a
      // save right after the checkpoint reports its inertial number with them).
      if (restart.has("/protocol/rate_and_direction")) {
        const auto rd = restart.reals("/protocol/rate_and_direction");
        if (rd.size() != 2 || !std::isfinite(rd[0]) || !(rd[0] > 0) ||
            (rd[1] != 1.0 && rd[1] != -1.0))
          throw InputError(ck.restart(k) +
                           ": /protocol/rate_and_direction is damaged; run "
                           "without --resume");
        rate_now = rd[0], direction_now = rd[1];
      }
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
      write_restart(r, "/restart", *sys);
      r.write("/protocol/rate_and_direction", std::vector<double>{rate_now, direction_now});
      r.commit();
    }
    save_moduli_part(ck.dir, ck.part(k), ck.fingerprint, out);
    write_text_file(ck.pointer(), std::to_string(k) + "\n");
    report_progress("variant " + label + ": stage " + std::to_string(k + 1) + " of " +
                    std::to_string(stages.size()) + " checkpointed");
    ck.remove(k - 1);
    if (stop()) return false;
  }
  // The finished variant is checkpointed first, then its stage pointer goes, then the stage
  // files: a kill between any two leaves either a finished variant or a pointer whose stage
  // is whole, never a pointer to removed files.
  save_moduli_part(ck.dir, ck.name, ck.fingerprint, out);
  std::filesystem::remove(ck.pointer());
  for (long k = 0; k < static_cast<long>(stages.size()); ++k) ck.remove(k);
  ck.remove(resumed);
  return true;
}

}  // namespace granular::moduli_study
