// The scenes the CLI can run: a scene file's top-level `scene = "<name>"` picks the driver.
#pragma once
#include <string>
#include <vector>

#include "core/io/scene_file.hpp"
#include "core/run/error.hpp"

namespace granular {

struct RunOptions {
  std::string out_dir;   // every output file of the run goes here
  bool progress = true;  // progress lines on stderr
  bool resume = false;   // continue from <out_dir>/checkpoint.h5 when the scene supports it
  bool charts = true;    // draw the PNG charts after the data is written
  // Wall-clock budget: a scene that checkpoints stops at its first checkpoint after this
  // many minutes (0: no budget); the run is continued with --resume.
  double stop_after_minutes = 0;
  // Read and check every key of the scene, then stop: nothing is written and nothing runs
  // (`granular check`, and the scene-file fuzz test).
  bool check_only = false;
};

using SceneRunner = void (*)(const SceneFile&, const RunOptions&);

struct SceneEntry {
  const char* name;
  const char* description;
  SceneRunner run;
  // The driver deals independent units (realizations, experiments, variants) over the ranks
  // of an MPI run; the others run on rank 0 alone.
  bool spreads_over_ranks = false;
};

const std::vector<SceneEntry>& scene_registry();

// The driver named by the file's `scene` key; an unknown name is an InputError that names
// the file and lists the known scenes.
const SceneEntry& find_scene(const SceneFile& scene);

// Every driver calls this once all its keys are read and checked, before it writes or
// computes anything: it creates the output directory and returns true, or in check mode
// returns false and the driver returns.
bool begin_outputs(const RunOptions& opts);

// With --resume, before begin_outputs: refuses ("--resume: no checkpoint at ...") when
// `checkpoint` (a file, or a folder of checkpoints) is missing or empty, so that a resume
// with nothing to continue leaves the folder as it was (a finished run's outputs included).
void require_checkpoint_to_resume(const RunOptions& opts, const std::string& checkpoint);

// In check mode, builds the run's first system with `build()` so that the run's guards (the
// time step against the stiffest contact, the dashpots) apply to `granular check` too; a
// guard's refusal is reported as an input error naming the scene file. Nothing in run mode.
template <class Build>
void check_first_system(const SceneFile& scene, const RunOptions& opts, Build&& build) {
  if (!opts.check_only) return;
  try {
    build();
  } catch (const PhysicsError& e) {
    throw InputError("scene file " + scene.path() + ": " + e.what());
  }
}

// Scene drivers (one per scenarios/scene_*.cpp file).
// DEM scenes
void run_two_particle_linear(const SceneFile&, const RunOptions&);
void run_isotropic_compression(const SceneFile&, const RunOptions&);
void run_hysteretic_collision(const SceneFile&, const RunOptions&);
void run_impact(const SceneFile&, const RunOptions&);
void run_impact_benchmarks(const SceneFile&, const RunOptions&);
void run_soft_collision(const SceneFile&, const RunOptions&);
void run_confined_compression(const SceneFile&, const RunOptions&);
void run_elastic_moduli(const SceneFile&, const RunOptions&);
// Reads and checks every key of an elastic_moduli scene without running it.
void check_elastic_moduli(const SceneFile&);
void run_mixture_moduli(const SceneFile&, const RunOptions&);
// Reads and checks every key of a mixture_moduli scene without running it.
void check_mixture_moduli(const SceneFile&);
// continuum law
void run_continuum_fit(const SceneFile&, const RunOptions&);
// Reads and checks every key of a continuum_fit scene without running it.
void check_continuum_fit(const SceneFile&);
// signals and waves
void run_signal_analysis(const SceneFile&, const RunOptions&);
void run_wave_transmission(const SceneFile&, const RunOptions&);
// LAMMPS decks: forces of LAMMPS' granular pair styles on a LAMMPS data file
void run_lammps_forces(const SceneFile&, const RunOptions&);
// chain scenes
void run_chain_impulse(const SceneFile&, const RunOptions&);
void run_chain_master_equation(const SceneFile&, const RunOptions&);
void run_chain_tones(const SceneFile&, const RunOptions&);

}  // namespace granular
