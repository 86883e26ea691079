// Initial states: a random, non-overlapping polydisperse gas in a periodic cube.
#pragma once
#include <cstdint>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "core/io/scene_file.hpp"

namespace granular {

struct GasSpec {
  int count = 0;
  double diameter_min = 1.0, diameter_max = 3.0;  // uniform distribution of diameters
  double density = 1.0;
  double phi = 0.3;        // volume fraction of the gas
  double speed = 0.0;      // standard deviation of each velocity component
  std::uint64_t seed = 1;  // all randomness derives from (seed, particle index)
};

// The densest gas random sequential insertion reaches reliably (it jams near 0.38 for equal
// spheres and somewhat above for polydisperse ones; a scene compresses from there).
constexpr double kMaxGasFraction = 0.45;

// Random sequential insertion, largest particles first; zero total momentum.
// Throws InputError when the requested volume fraction cannot be reached by insertion.
HostParticles random_gas(const GasSpec& spec, PeriodicBox& box);

// Checks a gas read from `scene` under the keys <table>.{diameter_min, diameter_max,
// density, initial_speed} and `phi_key`, before anything is allocated: sizes and density
// positive, a size ratio the neighbour grid can hold (<= 100), a box the doubles can
// measure, and a volume fraction in [1e-3, 0.45] (random insertion jams beyond).
void check_gas(const SceneFile& scene, const GasSpec& gas, const std::string& phi_key,
               const std::string& table = "particles");

// A starting packing from a file: the last frame of an H5MD file (`.h5md`, as the snapshot
// series writes them), a particle state group `group` of the engine's HDF5 files (`.h5`, e.g.
// results.h5's /final_state), or else a LAMMPS data file (atom style sphere, SI units). H5MD
// frames and states hold no density: `density` is given to every particle; data files carry
// their own. Throws InputError for an empty packing, a triclinic box or malformed data.
HostParticles read_packing_file(const std::string& path, double density, PeriodicBox& box,
                                const std::string& group = "/final_state");

}  // namespace granular
