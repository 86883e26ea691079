// Filling a box: random, non-overlapping insertion of a polydisperse set of spheres into a
// region (largest first; positions from the stream (seed, particle index), so the result
// does not depend on threads), and settling a DEM system until a kinetic-energy criterion
// holds. Periodic axes of the box wrap; on walled axes particles keep a radius from the
// region's faces.
#pragma once
#include <cstdint>
#include <functional>

#include "core/dem/box.hpp"
#include "core/dem/host_particles.hpp"

namespace granular {

struct FillSpec {
  int count = 0;
  double diameter_mean = 1.0;    // diameters uniform in mean (1 -+ spread)
  double diameter_spread = 0.0;  // relative half-width of the uniform distribution
  double density = 1.0;
  int species = 0;
  std::uint64_t seed = 1;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};  // insertion region
};

// Throws InputError (naming what to change) when a particle finds no free place.
HostParticles fill_region(const FillSpec& spec, const PeriodicBox& box);

// Steps `advance(n)` until `done()` holds, checking every `every` steps once `min_steps`
// have passed (particles inserted at rest satisfy any kinetic-energy criterion before they
// have fallen); returns the steps taken, or -1 if `max_steps` passed first.
long settle(const std::function<void(long)>& advance, const std::function<bool()>& done, long every,
            long max_steps, long min_steps = 0);

}  // namespace granular
