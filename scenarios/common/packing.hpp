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

}  // namespace granular
