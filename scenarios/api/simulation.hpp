// The engine as a library: one DEM simulation whose contact law is chosen at run time, and
// the stages the scene drivers are made of (strain to a volume fraction, relax, servo to a
// pressure, probe the moduli, save and restore), so that a protocol no driver has can be
// composed without writing C++. The Python package (scenarios/python/) is a front for this
// interface; docs/python.md describes both.
//
// Units are the engine's: mm, us, ug, so forces are in N, stresses in MPa, energies in mJ.
// Particle arrays are in identity order (the order the particles were given in), whatever
// order the engine keeps them in memory.
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/host_particles.hpp"
#include "core/dem/walls.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/contact_network.hpp"
#include "scenarios/common/element_test.hpp"
#include "scenarios/common/pressure_servo.hpp"

namespace granular::api {

// Particles and their periodic box, on the host.
struct Packing {
  HostParticles particles;
  PeriodicBox box;
};

// A random, non-overlapping polydisperse gas (scenarios/common/packing.hpp).
Packing random_packing(int count, double diameter_min, double diameter_max, double density,
                       double phi, std::uint64_t seed, double speed);
// A LAMMPS data file of atom style sphere in SI units (converted to mm, us, ug); refuses a
// triclinic box.
Packing read_lammps_packing(const std::string& path);
// A particle state group written by the engine (results.h5 /final_state, a snapshot).
Packing read_state_packing(const std::string& path, const std::string& group);

class Simulation {
 public:
  virtual ~Simulation();

  virtual void step(long n) = 0;
  // True strain rates of the box edges, per axis (negative: compression).
  virtual void set_strain_rate(const std::array<double, 3>& rate) = 0;
  virtual std::array<double, 3> strain_rate() const = 0;
  virtual double time() const = 0;
  virtual long steps() const = 0;
  virtual PeriodicBox box() const = 0;
  virtual const DemParams& params() const = 0;
  virtual int size() const = 0;
  virtual double particle_volume() const = 0;
  virtual double mass() const = 0;  // of all particles
  // The contact law's description: "linear", "hertz+coulomb", "materials+mindlin", ...
  virtual std::string model_name() const = 0;

  virtual Measurements measure() const = 0;
  // Stops a run that went wrong (NaN, runaway overlap) with a PhysicsError saying what to do.
  virtual void check_health(const Measurements& m) const = 0;
  virtual HostParticles particles() const = 0;     // positions wrapped into the box
  virtual std::vector<double> forces() const = 0;  // 3 per particle, of the last step
  virtual ContactNetwork contacts() const = 0;

  virtual void set_walls(const std::vector<WallSpec>& walls) = 0;
  virtual std::vector<WallLoad> wall_loads() const = 0;

  // Stages (scenarios/common/element_test.hpp and pressure_servo.hpp).
  virtual long strain_to_phi(double target, double rate, long every) = 0;
  virtual double relax(double ratio, long max_steps, long every) = 0;
  virtual ServoResult servo_to_pressure(double target, const ServoSettings& settings) = 0;
  // In place, keeping the contact history: each mode is strained, relaxed and reversed.
  virtual Moduli probe_moduli(double amplitude, long strain_steps, long relax_steps) = 0;
  // Each mode from a copy of the current state (which is left as it is), against a reference
  // run without strain; orientations 1 (xy, x) or 3 (all planes and axes).
  virtual Moduli probe_moduli_restarting(double amplitude, long strain_steps, long relax_steps,
                                         int orientations) = 0;

  // The complete state (history included), and a new simulation started from it.
  virtual ConfigState save() const = 0;
  virtual std::unique_ptr<Simulation> restart(const ConfigState& state) const = 0;

  // How many simulations are alive (the Python module finalizes Kokkos only at zero).
  static int alive();

 protected:
  Simulation();
};

// A simulation of `packing` under the contact law of a scene text: either a [contact] table
// (scenarios/common/contact_config.hpp) or [materials.<name>] tables with an optional
// [contact] (scenarios/common/materials.hpp). Keys are checked as in a scene file, so a
// misspelt key is refused naming it and `source`. The particles' species index the
// materials in name order.
std::unique_ptr<Simulation> make_simulation(const Packing& packing, const std::string& contact,
                                            const std::string& source, const DemParams& params);
// A simulation restarted from a saved state under the given contact law.
std::unique_ptr<Simulation> restore_simulation(const ConfigState& state, const std::string& contact,
                                               const std::string& source, const DemParams& params);

// Explicitly instantiated per contact law in simulation_<law>.cpp (one compilation each).
template <class Model>
std::unique_ptr<Simulation> simulation_of(const Model& model, const std::string& name,
                                          Particles<Kokkos::DefaultExecutionSpace> particles,
                                          std::vector<double> density, const PeriodicBox& box,
                                          const DemParams& params, const ConfigState* history);

}  // namespace granular::api
