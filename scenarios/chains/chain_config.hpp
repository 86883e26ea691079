// Scene keys shared by the chain scenes ([chain], [disorder], [time], [guard]) and the
// summary.json skeleton every chain scene writes.
#pragma once
#include <chrono>
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"
#include "kernels/chain/chain_batch.hpp"

namespace granular {

struct ChainScene {
  ChainSpec spec;           // xi is set per ensemble from `xis`
  std::vector<double> xis;  // disorder values, one ensemble each
  int realizations = 0;     // ensemble size
  bool exact = false;       // time.solver = "exact": the linearized chain's eigenmodes
  ChainKernel kernel = ChainKernel::Auto;  // time.kernel: which Verlet kernel (same bits)
  double dt = 0;             // Verlet time step (units of t_c); the sample interval if exact
  double sample_every = 0;   // time between samples
  double energy_growth = 0;  // divergence guard factor
};

ChainScene read_chain_scene(const SceneFile& scene);

// Steps per sample interval; the interval must be a whole number of time steps.
long chain_steps_per_sample(const SceneFile& scene, const ChainScene& c);

struct WallClock {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

}  // namespace granular
