// The elastic_moduli preparation protocol (docs/model_dem.md §6) for one variant, cut into
// stages that are checkpointed exactly, so that a study can stop at any stage and resume
// bit for bit.
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

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

// What one variant's preparation returns: its outputs (the preparation series, and the rows,
// sweeps and configurations `on_config` gave), whole where it `finished`, else as far as the
// run got before it stopped at a checkpoint.
struct Prepared {
  Outputs out;
  bool finished = false;
};

// Called with each relaxed configuration, its E_kin/E_pot and inertial number: what its
// probes gave, added to the variant's outputs.
using OnConfig = std::function<ConfigResults(const ConfigState&, double, double)>;

// The protocol for one variant: a list of stages (strains cut at every 0.02 in phi,
// relaxations, saved configurations); after each one the exact state and the outputs so far
// are checkpointed without touching the system, so the trajectory does not depend on where
// the stages fall, and a run resumed from any stage repeats the uninterrupted one bit for
// bit. The stages hold `this`: a Protocol is made where it is used and never moved.
template <class Model>
class Protocol {
 public:
  using System = DemSystem<Exec, Model>;

  Protocol(const Setup& s, size_t variant, const Model& model, const StageCheckpoints& ck,
           Progress& progress, long& done, const OnConfig& on_config)
      : s_(s),
        variant_(variant),
        model_(model),
        // With preparation.friction_from = "phi_0" the gas is compressed and relaxed without
        // friction and the preparation friction acts from the compression to phi_max on.
        gas_model_(s.friction_from_phi0 ? with_friction(model, 0.0) : model),
        ck_(ck),
        progress_(progress),
        done_(done),
        on_config_(on_config) {
    const PrepVariant& v = s.variants.at(variant);
    GasSpec gas = s.gas;
    gas.count = v.count, gas.seed = v.seed;
    density_ = gas.density;
    rate_now_ = s.rate;
    host_ = random_gas(gas, box_);
    double dsum = 0;
    for (double a : host_.radius) dsum += 2 * a;
    dbar_ = dsum / host_.size();
    sys_.emplace(Particles<Exec>::from_host(host_), box_, gas_model_, s.params);
    // P* = P dbar / k_n where k_n is a constant of the law (linear; hysteretic: k_2); a Hertz
    // stiffness depends on the overlaps, so its series keeps P only (P* is NaN).
    kn_fixed_ = s.contact.normal == "linear"       ? s.contact.linear.kn
                : s.contact.normal == "hysteretic" ? s.contact.hysteretic.k2
                                                   : kNaN;
    build_stages();
    label_ = v.tag.empty() ? ck.name : v.tag;  // in log lines
  }
  Protocol(const Protocol&) = delete;
  Protocol& operator=(const Protocol&) = delete;

  // The stage a resumed run continues after (-1: none), its outputs so far loaded.
  long checkpointed_stage() {
    if (!ck_.resume || !std::filesystem::exists(ck_.pointer())) return -1;
    std::ifstream in(ck_.pointer());
    long k = -1;
    if (!(in >> k) || k < 0)
      throw InputError(ck_.pointer() + ": not a stage number; remove the file to start the " +
                       "variant afresh, or run without --resume");
    if (!load_moduli_part(ck_.dir, ck_.part(k), ck_.fingerprint, out_))
      throw InputError(ck_.pointer() +
                       ": the checkpoint it names is missing; run without --resume");
    return k;
  }

  // Continues after stage k: the stages before count as done, and the system is made from
  // the checkpoint. Returns the first stage to run.
  long resume_after(long k) {
    const long last = static_cast<long>(stages_.size()) - 1;
    // A checkpoint at or past the last stage (written by a longer protocol, e.g. one that
    // still compressed on after the last saved configuration) already holds every saved
    // configuration: the preparation is complete.
    const long first = std::min(k + 1, last + 1);
    for (long q = 0; q < first; ++q) done_ += stages_[q].second ? 1 : 0;
    progress_.update(done_);
    if (first <= last) {
      restore(k);
      std::cerr << "variant " << label_ << ": continuing after stage " << k + 1 << " of "
                << stages_.size() << "\n";
    } else {
      std::cerr << "variant " << label_ << ": preparation complete in the checkpoint (stage "
                << k + 1 << ")\n";
    }
    return first;
  }

  // Runs the stages from `first`, each but the last checkpointed; false when `stop` asked to
  // end the run at a checkpoint.
  bool run_stages(long first, const std::function<bool()>& stop) {
    const auto started = std::chrono::steady_clock::now();
    const long n = static_cast<long>(stages_.size());
    for (long k = first; k < n; ++k) {
      stages_[k].first();
      if (stages_[k].second) progress_.update(++done_);
      if (k + 1 == n) break;  // the variant's part follows
      const Measurements m = sys_->measure();
      log_stage(k, m, started);
      checkpoint(k, m);
      ck_.remove(k - 1);
      if (stop()) return false;
    }
    return true;
  }

  // The finished variant is checkpointed first, then its stage pointer goes, then the stage
  // files: a kill between any two leaves either a finished variant or a pointer whose stage
  // is whole, never a pointer to removed files.
  void finish(long resumed) {
    save_moduli_part(ck_.dir, ck_.name, ck_.fingerprint, out_);
    std::filesystem::remove(ck_.pointer());
    for (long k = 0; k < static_cast<long>(stages_.size()); ++k) ck_.remove(k);
    ck_.remove(resumed);
  }

  Outputs& outputs() { return out_; }

 private:
  // One sample of the preparation series.
  void sample(const Measurements& m) {
    Outputs& out = out_;
    out.prep["phi"].push_back(m.phi), out.prep["pressure"].push_back(m.pressure);
    out.prep["z_corrected"].push_back(m.z_corrected);
    out.prep["volumetric_strain_rate"].push_back(rate_now_);
    out.prep["inertial_number"].push_back(
        m.pressure > 0 ? rate_now_ * dbar_ * std::sqrt(density_ / m.pressure) : kNaN);
    out.prep["variant"].push_back(static_cast<double>(variant_));
    out.prep["direction"].push_back(direction_now_);
    out.prep["pressure_star"].push_back(m.pressure * dbar_ / kn_fixed_);
    out.prep["ekin_over_epot"].push_back(m.epot > 0 ? m.ekin / m.epot : kNaN);
    for (int k = 0; k < 7; ++k)
      out.prep[k < 6 ? "contact_fraction_" + std::to_string(k) : "contact_fraction_6_or_more"]
          .push_back(m.contact_histogram[k]);
  }

  // Volumetric rate for the target inertial number, within [min_rate, rate].
  double rate_of(const Measurements& m) {
    double r = s_.rate;
    if (s_.prep_inertial > 0 && m.pressure > 0)
      r = std::clamp(s_.prep_inertial * std::sqrt(m.pressure / density_) / dbar_, s_.min_rate,
                     s_.rate);
    return rate_now_ = r;
  }

  void strain(double target, double sign) {
    rate_now_ = s_.rate;  // what the recorded series and I report (rate_of lowers it if adaptive)
    direction_now_ = -sign;  // a negative strain compresses
    std::function<double(const Measurements&)> f = nullptr;
    if (s_.prep_inertial > 0)
      f = [this, sign](const Measurements& m) { return sign * rate_of(m) / 3; };
    strain_to_phi(
        *sys_, target, sign * s_.rate / 3, 500, [this](const Measurements& m) { sample(m); }, f);
  }

  void compress_gas(double target) {
    rate_now_ = s_.gas_rate;
    direction_now_ = 1;
    strain_to_phi(*sys_, target, -s_.gas_rate / 3, 500,
                  [this](const Measurements& m) { sample(m); });
  }

  // Relaxes the state and hands it to on_config; what its probes gave joins the outputs.
  void save() {
    const double ratio = relax(*sys_, s_.relax_ratio, s_.relax_max, true);
    const Measurements m = sys_->measure();
    const double I = m.pressure > 0 ? rate_now_ * dbar_ * std::sqrt(density_ / m.pressure) : kNaN;
    out_.add(on_config_(snapshot(*sys_, host_.density, m.pressure), ratio, I));
  }

  // Strains from `from` to `to` (sign -1 compresses) in stages of 0.02 in phi.
  void add_strain(double from, double to, double sign, bool ends_step) {
    const double chunk = 0.02;
    const double up = -sign;  // compression (negative strain) raises phi
    for (double t = from + up * chunk; up * (to - t) > 1e-12; t += up * chunk)
      stages_.push_back({[this, t, sign] { strain(t, sign); }, false});
    stages_.push_back({[this, to, sign] { strain(to, sign); }, ends_step});
  }

  // The stages: work, and whether it ends a step of the protocol (for the progress line).
  void build_stages() {
    const Setup& s = s_;
    // 2. compress the gas to phi_0
    for (double t = s.gas.phi + 0.02; s.phi0 - t > 1e-12; t += 0.02)
      stages_.push_back({[this, t] { compress_gas(t); }, false});
    stages_.push_back({[this] { compress_gas(s_.phi0); }, true});
    stages_.push_back({[this] {
                         relax(*sys_, s_.relax_ratio, s_.relax_max);
                         sys_->set_model(model_);  // friction from here on (a no-op by default)
                       },
                       true});  // 3. relax
    relaxed_stage_ = static_cast<long>(stages_.size()) - 1;
    std::vector<double> sorted = s.targets;
    double from = s.phi0;
    if (s.loading_branch) {  // configurations on the way up (strongly cohesive samples)
      std::sort(sorted.begin(), sorted.end());
      for (double t : sorted)
        add_strain(from, t, -1, false), stages_.push_back({[this] { save(); }, true}), from = t;
      // No compression to phi_max after the last target: nothing is saved on it, and a
      // strongly cohesive packing that dense can run into the overlap limit.
    } else {
      add_strain(from, s.phi_max, -1, true);      // 4. compress to phi_max
      std::sort(sorted.rbegin(), sorted.rend());  // 5. unload, saving states
      from = s.phi_max;
      for (double t : sorted)
        add_strain(from, t, +1, false), stages_.push_back({[this] { save(); }, true}), from = t;
    }
  }

  // Makes the system from the checkpoint of stage k, and the protocol's rate and direction.
  void restore(long k) {
    if (!std::filesystem::exists(ck_.restart(k)))
      throw InputError(ck_.pointer() + ": the checkpoint predates exact restarts (no " +
                       ck_.restart(k) + "); run without --resume");
    // The saved state alone makes the system (no build nor force pass first).
    const H5Reader restart(ck_.restart(k));
    try {
      sys_.emplace(read_restart<System>(restart, "/restart"),
                   k < relaxed_stage_ ? gas_model_ : model_, s_.params, restart_origin("/restart"));
    } catch (const InputError& e) {
      throw InputError("--resume: " + ck_.restart(k) + ": " + e.what() + "; run without --resume");
    }
    // The protocol's own state: the rate and direction the next stage starts from (a save
    // right after the checkpoint reports its inertial number with them).
    if (restart.has("/protocol/rate_and_direction")) {
      const auto rd = restart.reals("/protocol/rate_and_direction");
      if (rd.size() != 2 || !std::isfinite(rd[0]) || !(rd[0] > 0) ||
          (rd[1] != 1.0 && rd[1] != -1.0))
        throw InputError(ck_.restart(k) +
                         ": /protocol/rate_and_direction is damaged; run "
                         "without --resume");
      rate_now_ = rd[0], direction_now_ = rd[1];
    }
  }

  // One line per stage: protocol steps last up to hours in a full study, and the progress
  // line only moves when one ends.
  void log_stage(long k, const Measurements& m,
                 std::chrono::steady_clock::time_point started) const {
    if (!progress_.enabled()) return;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    char line[160];
    std::snprintf(line, sizeof line, "variant %s: stage %ld/%zu done, phi %.4f, P %.4g, %.0fs\n",
                  label_.c_str(), k + 1, stages_.size(), m.phi, m.pressure, seconds);
    std::cerr << line;
  }

  // The state after stage k (a configuration and the exact restart), then the outputs so far,
  // then the pointer to them.
  void checkpoint(long k, const Measurements& m) {
    write_config(ck_.state(k), snapshot(*sys_, host_.density, m.pressure));
    {
      H5Writer r(ck_.restart(k));
      write_restart(r, "/restart", *sys_);
      r.write("/protocol/rate_and_direction", std::vector<double>{rate_now_, direction_now_});
      r.commit();
    }
    save_moduli_part(ck_.dir, ck_.part(k), ck_.fingerprint, out_);
    write_text_file(ck_.pointer(), std::to_string(k) + "\n");
    report_progress("variant " + label_ + ": stage " + std::to_string(k + 1) + " of " +
                    std::to_string(stages_.size()) + " checkpointed");
  }

  const Setup& s_;
  size_t variant_;
  Model model_, gas_model_;
  const StageCheckpoints& ck_;
  Progress& progress_;
  long& done_;
  const OnConfig& on_config_;
  PeriodicBox box_;
  HostParticles host_;
  double density_ = 0, dbar_ = 0, kn_fixed_ = kNaN;
  double rate_now_ = 0;
  double direction_now_ = 1;  // +1 compression, -1 decompression (the unloading branch)
  std::optional<System> sys_;
  std::vector<std::pair<std::function<void()>, bool>> stages_;
  long relaxed_stage_ = 0;
  std::string label_;
  Outputs out_;
};

// Runs the protocol for one variant (a run with --resume from its last checkpoint), calling
// `on_config` with each relaxed configuration. `variant` indexes s.variants: the preparation
// series are labelled with it (the jamming fit groups by it).
template <class Model>
Prepared prepare(const Setup& s, size_t variant, const Model& model, Progress& progress, long& done,
                 const StageCheckpoints& ck, const std::function<bool()>& stop,
                 const OnConfig& on_config) {
  Protocol<Model> protocol(s, variant, model, ck, progress, done, on_config);
  const long resumed = protocol.checkpointed_stage();  // the stage continued from
  const long first = resumed < 0 ? 0 : protocol.resume_after(resumed);
  Prepared p;
  p.finished = protocol.run_stages(first, stop);
  if (p.finished) protocol.finish(resumed);
  p.out = std::move(protocol.outputs());
  return p;
}

}  // namespace granular::moduli_study
