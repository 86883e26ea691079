// Scene `lammps_forces`: a LAMMPS data file (atom style sphere, orthogonal or triclinic
// periodic box) under a granular pair style written in LAMMPS' own terms; per-atom forces and
// torques and the pair virial at step 0 and after velocity-Verlet steps, as HDF5 and as a
// LAMMPS dump file (`dump custom` with id type xu yu zu vx vy vz omegax omegay omegaz fx fy fz
// tqx tqy tqz), so that a deck's output can be compared line by line and LAMMPS reads it.
#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/lammps/lammps_dump.hpp"
#include "core/lammps/lammps_forces.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

// One recorded state of the atoms: what results.h5, a dump file and the summary keep of a step.
struct LammpsState {
  long step = 0, contacts = 0;
  double kinetic_energy = 0;
  std::vector<double> x, v, omega, force, torque;  // 3 per atom
  std::array<double, 6> virial{};
};

// A run of the deck as data: the atoms, the box and each recorded state.
struct LammpsRun {
  std::vector<long> id;
  std::vector<int> type;
  LammpsBox box;
  std::vector<LammpsState> states;
  // What stopped the steps (a non-finite force, atoms the time step moved too far), raised
  // once the states before it are written: their dump files show where the atoms went.
  std::exception_ptr stopped;
  int size() const { return static_cast<int>(id.size()); }
};

// A LAMMPS dump frame of the atoms (`dump custom` columns, positions unwrapped).
std::string dump_text(const LammpsRun& run, const LammpsState& s) {
  LammpsDumpFrame f;
  f.step = s.step;
  const LammpsBox& b = run.box;
  for (int d = 0; d < 3; ++d) f.lo[d] = b.lo[d], f.len[d] = b.edge[d][d];
  f.tilt[0] = b.edge[1][0], f.tilt[1] = b.edge[2][0], f.tilt[2] = b.edge[2][1];
  f.triclinic = f.tilt[0] != 0 || f.tilt[1] != 0 || f.tilt[2] != 0;
  f.columns = {"id",     "type",   "xu", "yu", "zu", "vx",  "vy",  "vz", "omegax",
               "omegay", "omegaz", "fx", "fy", "fz", "tqx", "tqy", "tqz"};
  for (int i = 0; i < run.size(); ++i) {
    f.values.push_back(static_cast<double>(run.id[i]));
    f.values.push_back(run.type[i]);
    for (const std::vector<double>* a : {&s.x, &s.v, &s.omega, &s.force, &s.torque})
      for (int k = 0; k < 3; ++k) f.values.push_back((*a)[3 * i + k]);
  }
  return lammps_dump_text(f);
}

void check_finite(const LammpsForceField& ff) {
  for (int i = 0; i < ff.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(ff.force[3 * i + k]) || !std::isfinite(ff.torque[3 * i + k]) ||
          !std::isfinite(ff.x[3 * i + k]))
        throw PhysicsError("step " + std::to_string(ff.steps_done) + ": atom " +
                           std::to_string(ff.id[i]) +
                           " has a non-finite force, torque or position; use a smaller "
                           "lammps.timestep or check the pair coefficients");
}

Json state_json(const LammpsState& st, double volume, double nktv2p) {
  Json s = Json::object();
  s["step"] = st.step;
  s["contacts"] = st.contacts;
  s["kinetic_energy"] = st.kinetic_energy;
  Json w = Json::array(), p = Json::array();
  for (double c : st.virial) w.push(c), p.push(c / volume * nktv2p);
  s["pair_virial"] = w;           // xx yy zz xy xz yz
  s["pair_pressure_tensor"] = p;  // as LAMMPS' compute pressure ... pair
  return s;
}

// The units of the stored quantities: the data file's own, those of LAMMPS' unit style
// (LAMMPS' `units` page; velocities in length per time-step unit, as fix nve/sphere
// integrates them). The virial sums r f (energy units); torques are in energy units.
struct StyleUnits {
  std::string length, velocity, angular_velocity, force, torque, energy, pressure;
};
StyleUnits style_units(const std::string& style) {
  if (style == "si") return {"m", "m s-1", "rad s-1", "N", "N m", "J", "Pa"};
  if (style == "cgs") return {"cm", "cm s-1", "rad s-1", "dyn", "dyn cm", "erg", "dyn cm-2"};
  if (style == "micro")
    return {"um",           "um us-1",      "rad us-1",    "pg um us-2",
            "pg um+2 us-2", "pg um+2 us-2", "pg um-1 us-2"};
  if (style == "nano")
    return {"nm",           "nm ns-1",      "rad ns-1",    "ag nm ns-2",
            "ag nm+2 ns-2", "ag nm+2 ns-2", "ag nm-1 ns-2"};
  if (style == "real")
    return {"Angstrom",   "Angstrom fs-1", "rad fs-1", "kcal mol-1 Angstrom-1",
            "kcal mol-1", "kcal mol-1",    "atm"};
  if (style == "metal")
    return {"Angstrom", "Angstrom ps-1", "rad ps-1", "eV Angstrom-1", "eV", "eV", "bar"};
  if (style == "electron")
    return {"Bohr", "Bohr fs-1", "rad fs-1", "Hartree Bohr-1", "Hartree", "Hartree", "Pa"};
  // lj, the one style left (lammps_units refuses any other): LAMMPS' reduced units, every
  // quantity in terms of the deck's sigma (length), epsilon (energy), m (mass) and
  // tau = sigma sqrt(m / epsilon) (time).
  return {"1", "1", "1", "1", "1", "1", "1"};
}

void write_state(H5Writer& h5, const LammpsRun& run, const LammpsState& s,
                 const LammpsUnits& units) {
  const StyleUnits u = style_units(units.style);
  const double nktv2p = units.nktv2p;
  const std::string g = "/step_" + std::to_string(s.step);
  std::vector<double> ids(run.id.begin(), run.id.end());
  const std::vector<hsize_t> dims = {static_cast<hsize_t>(run.size()), 3};
  write_quantity(h5, g + "/id", ids, "1");
  write_quantity(h5, g + "/position", s.x, u.length, dims);
  write_quantity(h5, g + "/velocity", s.v, u.velocity, dims);
  write_quantity(h5, g + "/angular_velocity", s.omega, u.angular_velocity, dims);
  write_quantity(h5, g + "/force", s.force, u.force, dims);
  write_quantity(h5, g + "/torque", s.torque, u.torque, dims);
  std::vector<double> w(s.virial.begin(), s.virial.end()), p;
  for (double c : s.virial) p.push_back(c / run.box.volume() * nktv2p);
  write_quantity(h5, g + "/pair_virial", w, u.energy);
  write_quantity(h5, g + "/pair_pressure_tensor", p, u.pressure);
  h5.attribute(g, "contacts", static_cast<double>(s.contacts));
  h5.attribute(g, "kinetic_energy", s.kinetic_energy);
}

// The deck read from the scene: its data file, pair style and units, and the run.
struct LammpsSetup {
  LammpsUnits units;
  LammpsData data;
  LammpsPairModel model;
  std::unique_ptr<LammpsForceField> field;
  long steps = 0, every = 0;
};

// Every recorded state stays in memory until the run is written (LammpsState: 15 doubles per
// atom), so a deck whose run.steps / run.output_every would hold more than the machine has is
// refused before the force field is built or a step is taken.
void require_states_fit(const SceneFile& scene, long steps, long every, int atoms) {
  const double states = (every > 0 ? static_cast<double>(steps / every) : 0.0) + 2.0;
  try {
    scene.require_memory("run.steps", states * static_cast<double>(atoms) * 15.0 * 8.0);
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) +
                     ", or raise run.output_every (each recorded state holds every atom's "
                     "positions, velocities, spins, forces and torques until the end)");
  }
}

LammpsSetup read_setup(const SceneFile& scene) {
  LammpsSetup c;
  const std::string data_path = scene.input_path("lammps.data");
  c.units =
      scene.choice("lammps.units", "si", [](const std::string& s) { return lammps_units(s); });
  const std::string style = scene.text("lammps.pair_style");
  const std::vector<std::string> coeffs = scene.texts("lammps.pair_coeff");
  const double dt = scene.real("lammps.timestep");
  scene.require(dt > 0, "lammps.timestep", "must be positive");
  c.steps = scene.integer("run.steps", 0);
  scene.require(c.steps >= 0 && c.steps <= 1000000, "run.steps",
                "must lie in [0, 1e6]: this scene compares forces over a few steps");
  c.every = scene.integer("run.output_every", 0);
  scene.require(c.every >= 0, "run.output_every", "must not be negative (0: first and last step)");
  try {
    c.data = read_lammps_data(data_path, 1.0, 1.0, 1.0);  // in the file's own units
  } catch (const InputError& e) {
    scene.require(false, "lammps.data", e.what());
  }
  require_states_fit(scene, c.steps, c.every, c.data.particles.size());
  try {
    c.model = parse_lammps_pair(style, coeffs, c.data.atom_types, c.units);
  } catch (const InputError& e) {
    scene.require(false, "lammps.pair_coeff", e.what());
  }
  try {
    c.field = std::make_unique<LammpsForceField>(c.data, c.model, c.units, dt);
  } catch (const InputError& e) {
    scene.require(false, "lammps.data", e.what());
  }
  scene.reject_unknown_keys();
  return c;
}

LammpsState state_of(const LammpsForceField& ff) {
  LammpsState s;
  s.step = ff.steps_done, s.contacts = ff.contacts;
  s.kinetic_energy = ff.kinetic_energy();
  s.x = ff.x, s.v = ff.v, s.omega = ff.omega, s.force = ff.force, s.torque = ff.torque;
  s.virial = ff.virial;
  return s;
}

// LAMMPS' setup (forces of the initial state, history not advanced), then the steps: the
// states at step 0, every `every` steps and at the last.
LammpsRun run_deck(LammpsForceField& ff, const LammpsSetup& c, const std::string& scene_path,
                   bool progress) {
  LammpsRun run;
  run.id = ff.id, run.type = ff.type, run.box = ff.box;
  auto record = [&] {
    check_finite(ff);
    run.states.push_back(state_of(ff));
    if (progress)
      std::cerr << "lammps_forces: step " << ff.steps_done << " of " << c.steps << ", "
                << ff.contacts << " contacts\n";
  };
  try {
    ff.compute(false);
    record();
    for (long s = 1; s <= c.steps; ++s) {
      try {
        ff.step();
      } catch (const InputError& e) {  // from where the atoms went: the time step moved them
        throw PhysicsError(std::string(e.what()) + " at step " + std::to_string(ff.steps_done) +
                           ": lower lammps.timestep (" + scene_path + ")");
      }
      if (s == c.steps || (c.every > 0 && s % c.every == 0)) record();
    }
  } catch (...) {
    run.stopped = std::current_exception();
  }
  return run;
}

// Each state (results.h5, a dump file forces_step_<n>.lammpstrj and the summary), the atoms
// and the choices of the formulas.
void write_run(SceneOutput& output, const RunOptions& opts, const LammpsSetup& c,
               const LammpsRun& run) {
  H5Writer& h5 = output.h5();
  Json states = Json::array();
  for (const LammpsState& s : run.states) {
    write_state(h5, run, s, c.units);
    states.push(state_json(s, run.box.volume(), c.units.nktv2p));
    write_text_file(opts.out_dir + "/forces_step_" + std::to_string(s.step) + ".lammpstrj",
                    dump_text(run, s));
  }
  if (run.stopped) std::rethrow_exception(run.stopped);
  h5.attribute("/", "atoms", static_cast<double>(run.size()));
  h5.attribute("/", "volume", run.box.volume());
  h5.attribute("/", "pair_style", c.model.describe());

  Json& summary = output.summary();
  Json choices = Json::object();
  choices["pair_style"] = c.model.describe();
  choices["box"] = c.data.triclinic() ? "triclinic" : "orthogonal";
  choices["conventions"] =
      "LAMMPS' own formulas (the version Debian 12 ships): gran/* styles take the contact point "
      "at the particle surfaces and project the shear history after advancing it; granular "
      "takes it mid-overlap and rotates the history with its length kept; no history update "
      "while a run sets up (step 0); fix nve/sphere integration. Contacts are found every "
      "step (no skin).";
  summary["choices"] = choices;
  summary["atoms"] = run.size();
  summary["states"] = states;
}

}  // namespace

void run_lammps_forces(const SceneFile& scene, const RunOptions& opts) {
  LammpsSetup c = read_setup(scene);
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "lammps_forces");
  write_run(output, opts, c, run_deck(*c.field, c, scene.path(), opts.progress));
  output.finish();
  std::cout << "lammps_forces: " << c.field->size() << " atoms, " << c.model.describe() << ", "
            << c.steps << " steps; outputs in " << opts.out_dir << "\n";
}

}  // namespace granular
