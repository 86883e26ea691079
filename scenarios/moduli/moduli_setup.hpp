// The elastic_moduli scene's settings: preparation variants (size, seed, friction), the
// protocol's volume fractions and rates, probing amplitudes and the study's switches, read
// and checked from the scene file before anything runs.
#pragma once
#include <Kokkos_Core.hpp>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/io/scene_file.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/contact_config.hpp"
#include "scenarios/common/packing.hpp"

namespace granular::moduli_study {

using Exec = Kokkos::DefaultExecutionSpace;
inline const double kNaN = std::numeric_limits<double>::quiet_NaN();

// One preparation of the protocol: its size, seed and friction.
struct PrepVariant {
  int count = 0;
  std::uint64_t seed = 1;
  double mu = kNaN;  // preparation friction (NaN: as in [contact])
  double kc = kNaN;  // adhesive stiffness of the hysteretic law (NaN: as in [contact])
  double dt = kNaN;  // time step of this preparation and its probes (NaN: run.dt)
  std::string tag;   // subdirectory of configs/ and label in the table ("" if only one)
};

struct Setup {
  GasSpec gas;
  ContactConfig contact;
  DemParams params;
  std::vector<PrepVariant> variants;
  std::string start_from;  // probe this saved configuration instead of preparing
  // start.from read as another tool's packing (a LAMMPS data file, an H5MD frame, or a state
  // group named by start.from_group); null where it is a saved configuration (with springs).
  std::shared_ptr<const ConfigState> start_packing;
  double phi0 = 0.5, phi_max = 0.82, rate = 0, min_rate = 0, prep_inertial = 0, gas_rate = 0;
  bool loading_branch = false;
  bool friction_from_phi0 = false;  // gas compressed and relaxed without friction
  std::vector<double> targets;
  double relax_ratio = 1e-8;
  long relax_max = 200000;
  // Jamming density fit on the unloading branch: samples with 0 < P <= this (P* for laws of
  // constant stiffness, P for Hertz; 0: no fit, only the bracketing densities).
  double jamming_p_max = 1e-3;
  double amplitude = 3e-6, probe_inertial = 0;
  long strain_steps = 2000, probe_relax = 2000, max_strain_steps = 200000;
  bool keep_friction = false, halving = false;
  int orientations = 1;  // shear planes and uniaxial axes probed (1: xy and x; 3: all)
  // How much of the preparation this run does before it stops at a checkpoint (0: all):
  // variants, stages (a 0.02 step in phi, a relaxation or a saved configuration).
  long stop_after_variants = 0, stop_after_stages = 0;
  std::vector<double> kt_ratios;   // probing tangential stiffness over normal (empty: as prepared)
  std::vector<double> amplitudes;  // amplitude sweep (empty: none)
  bool sweep_same_steps = false;   // sweep in the base probe's steps instead of at its rate
  std::vector<double> prestrains;  // reversibility test (empty: none)
  double prestrain_relax_ratio = 1e-10;
};

// Reads every key of the scene (unknown keys are refused) and checks their ranges.
Setup read_setup(const SceneFile& scene);

// The settings a variant runs with: its own time step (preparation.dt), every step count of
// the protocol (probe strain and relaxation, the relaxation cap) rescaled so that it spans the
// same physical time as with run.dt. The rates are physical already.
Setup for_variant(const Setup& s, const PrepVariant& v);

}  // namespace granular::moduli_study
