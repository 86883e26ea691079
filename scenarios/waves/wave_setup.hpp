// Scene keys of `wave_transmission` (virtual transducers, docs/model_mixtures_and_waves.md §3).
//
//   [materials.<name>]  Hertz-Mindlin materials (materials.hpp); [contact] pair_rule etc.
//   [mixture]     materials = "glass, rubber"   volume_fractions = [0.9, 0.1]
//                 wall_material = "steel"   (frictionless walls: see wave_transmission.cpp)
//   [column]      length = 20 (bead diameters between the walls at the start, gas)
//                 width = 5 (periodic y and z, in diameters)   diameter = 4   spread = 0.05
//                 gas_volume_fraction = 0.35   seed = 1
//                 or from (a packing file: LAMMPS data, H5MD, or an .h5 state group
//                 from_group = "/final_state"), its species 0, 1, ... of the materials of
//                 mixture.materials in that order (no volume_fractions then): see
//                 column_from_file below
//   [preparation] pressures = [0.05, 0.2, 0.5] (MPa, wall stress sigma_xx, loading branch)
//                 friction = 0   wall_speed = 0.01 (mm/us, servo's largest)   damping_time
//                 tolerance = 0.02   relax_time   max_time   gas_end_phi = 0.55
//                 max_push = 0.003 (largest servo step, fraction of the gap)
//                 final_relax_time (us, the state must stay within tolerance over it)
//                 unconverged = "skip" | "stop" (a target the servo does not reach within
//                 max_time: left out of the analysis and listed in summary.json's
//                 unconverged_states, the next target prepared from where it stopped; or the
//                 run stops with the servo's last held states)
//   [pulse]       shape = "raised_cosine" | "ricker"   duration (us)   velocity (mm/us)
//                 amplitude_factors = [1, 2]   pre_time (us, quiet record before the pulse)
//                 record_time (us)   sample_every (steps)
//   [receivers]   slab_positions = [0.3, 0.7] (fractions of the wall gap)   slab_width = 2 (d)
//   [probe]       strain = 1e-5   ramp_time   hold_time   damping_time
//   [analysis.*]  pickers, spectrum windows, ratio band (signal_report.hpp)
//   [run]         dt   max_overlap   dt_check = [factors]  (travel time and Q against dt x factor)
//                 restitution_check = [e, ...]  (travel time and Q with every material's
//                 restitution set to e: 1 = no contact damping, what scattering alone leaves)
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/host_particles.hpp"
#include "core/io/scene_file.hpp"
#include "scenarios/common/materials.hpp"
#include "scenarios/waves/signal_report.hpp"

namespace granular {

struct WaveSetup {
  MaterialSet mats;
  std::vector<int> species;       // material slots of the particles' species
  std::vector<double> fractions;  // their volume fractions (sum 1)
  int wall = 0;
  double length = 20, width = 5, diameter = 4, spread = 0.05, gas_phi = 0.35;
  long seed = 1;
  std::optional<HostParticles> from;  // column.from: the packing file's particles
  PeriodicBox from_box;               // and the column they fill (walls at x = 0 and len[0])
  std::vector<double> pressures;
  double prep_friction = 0, wall_speed = 0.01, damping_time = 0, tolerance = 0.02;
  double relax_time = 0, max_time = 0, gas_end_phi = 0.55, max_push = 0.003;
  double final_relax_time = 0;
  bool stop_unconverged = false;  // preparation.unconverged = "stop"
  std::string shape = "raised_cosine";
  double duration = 0, velocity = 0, pre_time = 0, record_time = 0;
  std::vector<double> amplitude_factors;
  long sample_every = 10;
  std::vector<double> slab_positions;
  double slab_width = 2;
  double probe_strain = 1e-5, probe_ramp = 0, probe_hold = 0, probe_damping_time = 0;
  double dt = 0, max_overlap = 0.05;
  std::vector<double> dt_check;
  std::vector<double> restitution_check;
  SignalSettings signals;
};

WaveSetup read_wave_setup(const SceneFile& scene);

// column.from: another tool's packing as the column's gas. Its particle of species k is of the
// k-th material of mixture.materials (density included); the walls stand at the particles'
// extent along x (a periodic packing keeps its width in y and z, which must be 3 mean
// diameters or more), so no particle starts inside a wall. Sets w.from, w.from_box, and from
// the file: fractions (by volume), diameter (the mean), length and width (in it).
void column_from_file(const SceneFile& scene, WaveSetup& w);

// Velocity of the source wall (into the sample) at time t, and its displacement.
double pulse_velocity(const WaveSetup& w, double amplitude, double t);
double pulse_displacement(const WaveSetup& w, double amplitude, double t);

}  // namespace granular
