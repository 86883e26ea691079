#include "scenarios/chains/chain_config.hpp"

#include <cmath>

namespace granular {

ChainScene read_chain_scene(const SceneFile& scene) {
  ChainScene c;
  c.spec.beads = scene.count("chain.beads", 2, 8.0 * 16);
  c.spec.boundary = scene.choice("chain.boundary", "fixed", parse_chain_boundary);
  c.spec.force = scene.choice("chain.force", "hertz", parse_chain_force);
  c.spec.rule = scene.choice("chain.stiffness_rule", "radius", parse_stiffness_rule);
  c.spec.target = scene.choice("disorder.on", "mass_and_stiffness", parse_disorder_target);
  c.spec.seed = static_cast<std::uint64_t>(scene.integer("disorder.seed", 1));
  c.xis = scene.reals("disorder.xi");
  c.realizations = scene.count("disorder.realizations", 1, 0.0);
  // Every realization holds every bead's state (about 16 doubles per bead).
  scene.require_memory("disorder.realizations",
                       16.0 * 8.0 * c.spec.beads * c.realizations * c.xis.size());
  c.spec.min_mass = scene.real("disorder.min_mass", 0.0);
  scene.require(c.spec.min_mass >= 0 && c.spec.min_mass < 1, "disorder.min_mass",
                "must be in [0, 1) (the mean mass is 1)");
  const std::string solver = scene.text("time.solver", "verlet");
  scene.require(solver == "verlet" || solver == "exact", "time.solver",
                "must be \"verlet\" (the chain of chain.force, stepped) or \"exact\" (the "
                "linearized chain's eigenmodes, evaluated at the sample times)");
  c.exact = solver == "exact";
  c.kernel = scene.choice("time.kernel", "auto", parse_chain_kernel);
  c.sample_every = scene.real("time.sample_every");
  scene.require(!c.exact || c.spec.force == ChainForce::Linear, "time.solver",
                "\"exact\" solves the linearized chain: set chain.force = \"linear\"");
  // The exact solution has no time step (and no stability limit: no mass floor needed).
  c.dt = c.exact ? c.sample_every : scene.real("time.dt");
  c.energy_growth = scene.real("guard.energy_growth", 1e4);
  scene.require(c.spec.beads >= 2, "chain.beads", "must be at least 2");
  scene.require(c.realizations >= 1, "disorder.realizations", "must be at least 1");
  scene.require(!c.xis.empty(), "disorder.xi", "must list at least one disorder value");
  for (double xi : c.xis)
    scene.require(xi >= 0 && xi < 1, "disorder.xi", "values must be in [0, 1)");
  scene.require(c.sample_every > 0, "time.sample_every", "must be positive");
  if (c.exact) return c;
  scene.require(c.dt > 0, "time.dt", "must be positive");
  // 2/omega_max of the ordered chain; disorder lowers it further (lighter beads), which
  // the divergence guard catches at run time.
  const double edge = 2.0 / (2.0 * std::sqrt(1.5));
  scene.require(c.dt < edge, "time.dt",
                "must be below the Verlet stability limit 2/omega_max = " + std::to_string(edge) +
                    " of the ordered chain");
  scene.require(c.sample_every >= c.dt && c.sample_every <= 1e6 * c.dt, "time.sample_every",
                "must lie between one and 1e6 time steps");
  scene.require(c.energy_growth > 1, "guard.energy_growth", "must be greater than 1");
  return c;
}

long chain_steps_per_sample(const SceneFile& scene, const ChainScene& c) {
  const long steps = std::lround(c.sample_every / c.dt);
  scene.require(std::abs(steps * c.dt - c.sample_every) < 1e-9 * c.sample_every,
                "time.sample_every", "must be a whole number of time steps time.dt");
  return steps;
}

}  // namespace granular
