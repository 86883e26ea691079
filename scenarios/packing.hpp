// Initial states: a random, non-overlapping polydisperse gas in a periodic cube.
#pragma once
#include <cstdint>

#include "core/box.hpp"
#include "core/particles.hpp"

namespace granular {

struct GasSpec {
  int count = 0;
  double diameter_min = 1.0, diameter_max = 3.0;  // uniform distribution of diameters
  double density = 1.0;
  double phi = 0.3;        // volume fraction of the gas
  double speed = 0.0;      // standard deviation of each velocity component
  std::uint64_t seed = 1;  // all randomness derives from (seed, particle index)
};

// Random sequential insertion, largest particles first; zero total momentum.
// Throws InputError when the requested volume fraction cannot be reached by insertion.
HostParticles random_gas(const GasSpec& spec, PeriodicBox& box);

}  // namespace granular
