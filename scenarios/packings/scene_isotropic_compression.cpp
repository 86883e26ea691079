// Scene `isotropic_compression` (the default main job): a random polydisperse gas is
// compressed isotropically at a constant volumetric strain rate to a dense packing, then
// relaxed at constant volume. Records P, Z, E_kin/E_pot against phi; checkpoints so an
// interrupted run can resume (--resume).
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/progress.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/contact_config.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/packing_file.hpp"
#include "scenarios/common/restart_file.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/common/snapshot_series.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

using Exec = Kokkos::DefaultExecutionSpace;
using System = DemSystem<Exec, FrictionlessLinear>;

// Columns of the time series, in file order.
const char* const kSeries[] = {"time",
                               "step",
                               "phi",
                               "pressure",
                               "pressure_star",
                               "z",
                               "z_corrected",
                               "rattler_fraction",
                               "ekin",
                               "epot",
                               "ekin_over_epot",
                               "max_overlap",
                               "stress_xx",
                               "stress_yy",
                               "stress_zz",
                               "neighbor_builds",
                               "phase"};
// Their units (mm, us, ug: stresses in MPa, energies in mJ). pressure_star is P <d> / k_n;
// max_overlap is the largest delta / min(a_i, a_j); phase is 0 (compression) or 1 (relaxation).
const char* const kSeriesUnits[] = {
    "us",   // time
    "1",    // step
    "1",    // phi
    "MPa",  // pressure
    "1",    // pressure_star
    "1",    // z
    "1",    // z_corrected
    "1",    // rattler_fraction
    "mJ",   // ekin
    "mJ",   // epot
    "1",    // ekin_over_epot
    "1",    // max_overlap
    "MPa",  // stress_xx
    "MPa",  // stress_yy
    "MPa",  // stress_zz
    "1",    // neighbor_builds
    "1",    // phase
};
static_assert(std::size(kSeries) == std::size(kSeriesUnits), "a unit for every column");

struct Series {
  std::map<std::string, std::vector<double>> col;
  void add(const System& sys, const Measurements& m, double d_mean, double phase) {
    const double kn = sys.model().normal.table.p[0][0].kn;
    const double vals[] = {sys.time(),
                           static_cast<double>(sys.steps()),
                           m.phi,
                           m.pressure,
                           m.pressure * d_mean / kn,
                           m.z,
                           m.z_corrected,
                           m.rattlers / sys.particles().n,
                           m.ekin,
                           m.epot,
                           m.epot > 0 ? m.ekin / m.epot : NAN,
                           m.max_overlap,
                           m.stress[0],
                           m.stress[1],
                           m.stress[2],
                           static_cast<double>(sys.neighbor_list().builds()),
                           phase};
    for (size_t c = 0; c < std::size(kSeries); ++c) col[kSeries[c]].push_back(vals[c]);
  }
  void write(H5Writer& out, const std::string& group) const {
    for (const auto& [name, v] : col) out.write(group + "/" + name, v);
    for (size_t c = 0; c < std::size(kSeries); ++c)
      if (col.count(kSeries[c])) set_unit(out, group + "/" + kSeries[c], kSeriesUnits[c]);
  }
  void read(const H5Reader& in, const std::string& group) {
    for (const char* name : kSeries) col[name] = in.reals(group + "/" + name);
  }
};

// The scene's keys, read and checked. The start: a random gas, or a packing from a file
// (particles.from: LAMMPS data, an H5MD series' last frame or a state group), compressed from
// its own volume fraction.
struct IsoSetup {
  std::string from;
  GasSpec gas;  // the gas, or the sizes, density and volume fraction of the packing read
  HostParticles start;
  PeriodicBox start_box;
  double phi_end = 0, rate = 0, kn = 0, gn = 0;
  long relax_steps = 0, sample_every = 0, checkpoint_every = 0;
  // Stop as if interrupted after this many steps (0: never), leaving the checkpoint behind;
  // used to test that --resume reproduces an uninterrupted run.
  long stop_after = 0;
  // ParaView time series: a frame at the first sample at or after every k steps (0: none).
  long snapshot_every = 0;
  bool with_contacts = false;
  DemParams params;
  FrictionlessLinear model() const { return {LinearNormal::uniform(kn, gn), {}, {}}; }
  double d_mean() const { return 0.5 * (gas.diameter_min + gas.diameter_max); }
};

// particles.from: the packing read, and its count, density, sizes and volume fraction.
void read_packing_start(const SceneFile& scene, IsoSetup& s) {
  GasSpec& gas = s.gas;
  s.start = read_scene_packing(scene, "particles.from", s.from, "particles.density",
                               scene.text("particles.from_group", "/final_state"), s.start_box);
  gas.count = s.start.size();
  gas.density = s.start.density[0];
  for (double d : s.start.density)
    scene.require(d == gas.density && d > 0, "particles.from",
                  "holds particles of different or non-positive densities; this scene "
                  "keeps one density");
  const auto [rmin, rmax] = std::minmax_element(s.start.radius.begin(), s.start.radius.end());
  gas.diameter_min = 2 * *rmin, gas.diameter_max = 2 * *rmax;
  double volume = 0;
  for (double r : s.start.radius) volume += 4.0 / 3.0 * M_PI * r * r * r;
  gas.phi = volume / s.start_box.volume();
}

IsoSetup read_setup(const SceneFile& scene) {
  IsoSetup s;
  GasSpec& gas = s.gas;
  s.from = scene.optional_input_path("particles.from");
  if (s.from.empty()) {
    gas.count = scene.count("particles.count", 2, kDemBytesPerParticle);
    gas.diameter_min = scene.real("particles.diameter_min");
    gas.diameter_max = scene.real("particles.diameter_max");
    gas.density = scene.real("particles.density");
    gas.seed = static_cast<std::uint64_t>(scene.integer("particles.seed", 1));
    gas.speed = scene.real("particles.initial_speed", 0.0);
    gas.phi = scene.real("compression.phi_start");
  } else {
    read_packing_start(scene, s);
  }
  s.phi_end = scene.real("compression.phi_end");
  s.rate = scene.real("compression.volumetric_strain_rate");
  s.relax_steps = scene.integer("compression.relax_steps", 0);
  const LinearNormal::Params law = read_linear_normal(scene, std::nullopt);  // gamma_n required
  s.kn = law.kn, s.gn = law.gn;
  DemParams& params = s.params;
  params.dt = scene.real("run.dt");
  scene.require(params.dt > 0, "run.dt", "must be positive");
  params.dt_key = "run.dt";
  params.skin = scene.real("run.skin");
  params.damping.translational = scene.real("damping.background", 0.0);
  params.damping.rotational = scene.real("damping.rotational", 0.0);
  params.rattler_threshold = scene.small_integer("run.rattler_threshold", 3);
  params.max_overlap = scene.real("run.max_overlap", 0.3);
  s.sample_every = scene.integer("run.sample_every", 500);
  s.checkpoint_every = scene.integer("run.checkpoint_every", 100000);
  s.stop_after = scene.integer("run.stop_after", 0);
  s.snapshot_every = scene.integer("output.snapshot_every", 0);
  if (s.from.empty()) {
    scene.require(gas.count >= 2, "particles.count", "must be at least 2");
    check_gas(scene, gas, "compression.phi_start");
  }
  scene.require(s.phi_end > gas.phi && s.phi_end < 1.0, "compression.phi_end",
                s.from.empty() ? "must lie between compression.phi_start and 1"
                               : "must lie between the packing's volume fraction (" +
                                     std::to_string(gas.phi) + ") and 1");
  scene.require(s.rate > 0, "compression.volumetric_strain_rate", "must be positive");
  scene.require(params.skin > 0, "run.skin", "must be positive");
  scene.require(s.sample_every > 0, "run.sample_every", "must be positive");
  scene.require(s.checkpoint_every > 0, "run.checkpoint_every", "must be positive");
  scene.require(s.relax_steps >= 0 && s.relax_steps <= 100000000, "compression.relax_steps",
                "must lie in [0, 1e8]");
  scene.require(s.snapshot_every >= 0, "output.snapshot_every", "must not be negative");
  s.with_contacts = snapshot_contacts(scene);
  scene.require(!s.with_contacts || s.snapshot_every > 0, "output.snapshot_contacts",
                "needs output.snapshot_every > 0 (the frames it adds the network to)");
  scene.reject_unknown_keys();
  return s;
}

// The run's system: made from the checkpoint's restart group (and its series so far) when the
// run resumes, else from the gas or the packing read.
System make_system(const IsoSetup& s, bool resume, const std::string& checkpoint, Series& series) {
  if (resume) {  // the saved state alone makes the system (no build nor force pass first)
    H5Reader in(checkpoint);
    if (!in.has("/restart"))
      throw InputError("--resume: " + checkpoint + " predates exact restarts; run afresh");
    try {
      const System::Saved saved = read_restart<System>(in, "/restart");
      series.read(in, "/series");
      std::cerr << "resuming from " << checkpoint << " at step " << saved.steps << "\n";
      return System(saved, s.model(), s.params, restart_origin("/restart"));
    } catch (const InputError& e) {
      throw InputError("--resume: " + checkpoint + ": " + e.what() + "; run afresh");
    }
  }
  PeriodicBox box;
  HostParticles host;
  if (s.from.empty()) {
    host = random_gas(s.gas, box);
  } else {
    host = s.start, box = s.start_box;
  }
  return System(Particles<Exec>::from_host(host), box, s.model(), s.params);
}

// The checkpoint: the system's exact state and the series so far. It changes nothing in the
// system, so the run does not depend on run.checkpoint_every and a resumed run repeats the
// uninterrupted one bit for bit.
void save_checkpoint(const std::string& checkpoint, const System& sys, const Series& series) {
  H5Writer out(checkpoint);
  write_restart(out, "/restart", sys);
  series.write(out, "/series");
  out.commit();
}

// After a physical failure: the last state (last_state.h5 and its XDMF file) and the snapshot
// frames up to the failure, which show how it came about.
void leave_last_state(const IsoSetup& s, const RunOptions& opts, const System& sys,
                      SnapshotSeries& snapshots) {
  H5Writer out(opts.out_dir + "/last_state.h5");
  write_state(out, "/state", sys.particles(), sys.box(), s.gas.density);
  out.commit();
  write_xdmf(opts.out_dir + "/last_state.xdmf", "last_state.h5",
             {state_frame("/state", sys.particles().n)}, false);
  try {
    snapshots.finish(sys);
  } catch (const std::exception& e) {
    std::cerr << "warning: snapshot series not written: " << e.what() << "\n";
  }
}

// Records a snapshot frame if one is due; true when it did.
bool sample_frame(SnapshotSeries& snapshots, const System& sys) {
  const int frames = snapshots.frames();
  snapshots.sample(sys);
  return snapshots.frames() > frames;
}

// Compresses at the volumetric rate to phi_end, then relaxes at constant volume, sampling the
// series and checkpointing as it goes; false when it stopped at run.stop_after. `framed`: whether
// the snapshot series' last frame holds the end state. A physical failure leaves the last state
// and the frames so far, then goes on up.
bool compress_and_relax(const IsoSetup& s, const RunOptions& opts, const std::string& checkpoint,
                        System& sys, Series& series, SnapshotSeries& snapshots, bool& framed) {
  const long step0 = sys.steps();  // where this run starts: 0, or the checkpoint's step
  // Per-axis rate for the volumetric rate: V(t) = V0 exp(-rate t) in the limit dt -> 0.
  const double axis_rate = -s.rate / 3.0;
  const double shrink_per_step = std::pow(1.0 + axis_rate * s.params.dt, 3);
  const long compress_steps =
      static_cast<long>(std::ceil(std::log(s.phi_end / s.gas.phi) / -std::log(shrink_per_step)));
  const long total_steps = compress_steps + s.relax_steps;
  const double d_mean = s.d_mean();
  try {
    if (series.col.empty()) series.add(sys, sys.measure(), d_mean, 0);
    framed = sample_frame(snapshots, sys);
    Progress progress("isotropic compression", total_steps - step0, opts.progress);
    while (sys.steps() < total_steps) {
      const bool compressing = sys.steps() < compress_steps;
      const long phase_end = compressing ? compress_steps : total_steps;
      const long next_sample = (sys.steps() / s.sample_every + 1) * s.sample_every;
      const long next_checkpoint = (sys.steps() / s.checkpoint_every + 1) * s.checkpoint_every;
      const long n = std::min({phase_end, next_sample, next_checkpoint}) - sys.steps();
      // The strain rate of the steps about to be taken (compression, then relaxation).
      const double r = compressing ? axis_rate : 0.0;
      sys.set_strain_rate(r, r, r);
      sys.step(n);
      const Measurements m = sys.measure();
      sys.check_health(m);
      series.add(sys, m, d_mean, compressing ? 0 : 1);
      framed = sample_frame(snapshots, sys);
      char extra[96];
      std::snprintf(extra, sizeof extra, "phi %.4f  P* %.2e  Z %.2f", m.phi,
                    m.pressure * d_mean / s.kn, m.z_corrected);
      progress.update(sys.steps() - step0, extra);
      if (sys.steps() / s.checkpoint_every != (sys.steps() - n) / s.checkpoint_every)
        save_checkpoint(checkpoint, sys, series);
      if (s.stop_after > 0 && sys.steps() >= s.stop_after) {
        std::cerr << "stopped after step " << sys.steps()
                  << " (run.stop_after); continue with --resume\n";
        return false;
      }
    }
  } catch (const PhysicsError&) {
    leave_last_state(s, opts, sys, snapshots);
    throw;
  }
  return true;
}

// A complete run: the series, the end state and its figures, and the snapshot series' closing
// frame where its last frame is not the end state.
struct IsoRun {
  Series series;
  Particles<Exec> final_state;  // the system's particle arrays at the end
  PeriodicBox box;
  Measurements fin;
  long steps = 0, neighbor_builds = 0;
  double time = 0;
  std::optional<SnapshotFrame> closing_frame;
};

// Makes the system (afresh or from the checkpoint), compresses and relaxes it and returns the
// run; nothing when it stopped at run.stop_after.
std::optional<IsoRun> run_compression(const IsoSetup& s, const RunOptions& opts,
                                      const std::string& checkpoint, SnapshotSeries& snapshots) {
  IsoRun run;
  System sys = make_system(s, opts.resume, checkpoint, run.series);
  bool framed = false;
  if (!compress_and_relax(s, opts, checkpoint, sys, run.series, snapshots, framed))
    return std::nullopt;
  run.fin = sys.measure();
  run.steps = sys.steps(), run.time = sys.time();
  run.neighbor_builds = sys.neighbor_list().builds();
  run.final_state = sys.particles(), run.box = sys.box();
  if (snapshots.enabled() && !framed) run.closing_frame = snapshots.frame_with_contacts(sys);
  return run;
}

// The end state's figures in summary.json.
Json final_results(const IsoSetup& s, const IsoRun& run) {
  const double d_mean = s.d_mean();
  const Measurements& fin = run.fin;
  // Volume fraction where a finite pressure first appears (P* > 1e-5) during compression.
  const auto& phi = run.series.col.at("phi");
  const auto& pstar = run.series.col.at("pressure_star");
  double phi_onset = NAN;
  for (size_t i = 0; i < phi.size(); ++i)
    if (run.series.col.at("phase")[i] == 0 && pstar[i] > 1e-5) {
      phi_onset = phi[i];
      break;
    }
  Json res = Json::object();
  res["particles"] = s.gas.count;
  res["steps"] = run.steps;
  res["simulated_time"] = run.time;
  res["phi_final"] = fin.phi;
  res["pressure_final"] = fin.pressure;
  res["pressure_star_final"] = fin.pressure * d_mean / s.kn;
  res["z_final"] = fin.z;
  res["z_corrected_final"] = fin.z_corrected;
  res["rattler_fraction_final"] = fin.rattlers / s.gas.count;
  res["ekin_over_epot_final"] =
      fin.epot > 0 ? Json(fin.ekin / fin.epot) : Json();  // undefined in a gas
  res["max_overlap_final"] = fin.max_overlap;
  res["phi_pressure_onset"] = std::isnan(phi_onset) ? Json() : Json(phi_onset);  // none reached
  res["neighbor_builds"] = run.neighbor_builds;
  // Volumetric inertial number at the end of compression, I_v = rate <d> sqrt(rho / P).
  res["inertial_number_final"] =  // undefined without pressure
      fin.pressure > 0 ? Json(s.rate * d_mean * std::sqrt(s.gas.density / fin.pressure)) : Json();
  return res;
}

// results.h5 (the series, the end state, the scene's constants) and the end state's XDMF file,
// then the snapshot series closed with its last frame, then summary.json.
void write_run(const SceneFile& scene, const RunOptions& opts, const IsoSetup& s, const IsoRun& run,
               SnapshotSeries& snapshots) {
  SceneOutput output(scene, opts, "isotropic_compression");
  H5Writer& h5 = output.h5();
  run.series.write(h5, "/series");
  write_state(h5, "/final_state", run.final_state, run.box, s.gas.density);
  h5.attribute("/", "scene", std::string("isotropic_compression"));
  h5.attribute("/", "kn", s.kn);
  h5.attribute("/", "mean_diameter", s.d_mean());
  output.commit_results();
  write_xdmf(opts.out_dir + "/final_state.xdmf", "results.h5",
             {state_frame("/final_state", run.final_state.n)}, false);
  if (snapshots.enabled()) {
    if (run.closing_frame) snapshots.append(*run.closing_frame);
    snapshots.commit();
  }
  output.summary()["results"] = final_results(s, run);
  output.finish();
}

}  // namespace

void run_isotropic_compression(const SceneFile& scene, const RunOptions& opts) {
  const IsoSetup s = read_setup(scene);
  check_first_system(scene, opts, [&] {  // the same gas as the run's, thrown away
    PeriodicBox first_box = s.start_box;
    System(Particles<Exec>::from_host(s.from.empty() ? random_gas(s.gas, first_box) : s.start),
           first_box, s.model(), s.params);
  });
  const std::string checkpoint = opts.out_dir + "/checkpoint.h5";
  require_checkpoint_to_resume(opts, checkpoint);
  if (!begin_outputs(opts)) return;
  // A resumed run's snapshot series starts where it resumed; an interrupted one leaves none.
  SnapshotSeries snapshots(opts.out_dir, "snapshots", s.snapshot_every);
  snapshots.record_contacts(s.with_contacts);
  const std::optional<IsoRun> run = run_compression(s, opts, checkpoint, snapshots);
  if (!run) return;  // stopped at run.stop_after, the checkpoint left behind
  write_run(scene, opts, s, *run, snapshots);
  std::error_code ec;
  std::filesystem::remove(checkpoint, ec);  // the run is complete: results.h5 supersedes it
}

}  // namespace granular
