// Scene `lammps_forces`: a LAMMPS data file (atom style sphere, orthogonal or triclinic
// periodic box) under a granular pair style written in LAMMPS' own terms; per-atom forces and
// torques and the pair virial at step 0 and after velocity-Verlet steps, as HDF5 and as a
// LAMMPS dump file (`dump custom` with id type xu yu zu vx vy vz omegax omegay omegaz fx fy fz
// tqx tqy tqz), so that a deck's output can be compared line by line and LAMMPS reads it.
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/lammps/lammps_dump.hpp"
#include "core/lammps/lammps_forces.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

// A LAMMPS dump frame of the atoms (`dump custom` columns, positions unwrapped).
std::string dump_text(const LammpsForceField& ff) {
  LammpsDumpFrame f;
  f.step = ff.steps_done;
  const LammpsBox& b = ff.box;
  for (int d = 0; d < 3; ++d) f.lo[d] = b.lo[d], f.len[d] = b.edge[d][d];
  f.tilt[0] = b.edge[1][0], f.tilt[1] = b.edge[2][0], f.tilt[2] = b.edge[2][1];
  f.triclinic = f.tilt[0] != 0 || f.tilt[1] != 0 || f.tilt[2] != 0;
  f.columns = {"id",     "type",   "xu", "yu", "zu", "vx",  "vy",  "vz", "omegax",
               "omegay", "omegaz", "fx", "fy", "fz", "tqx", "tqy", "tqz"};
  for (int i = 0; i < ff.size(); ++i) {
    f.values.push_back(static_cast<double>(ff.id[i]));
    f.values.push_back(ff.type[i]);
    for (const std::vector<double>* a : {&ff.x, &ff.v, &ff.omega, &ff.force, &ff.torque})
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

Json state_json(const LammpsForceField& ff, double nktv2p) {
  Json s = Json::object();
  s["step"] = ff.steps_done;
  s["contacts"] = ff.contacts;
  s["kinetic_energy"] = ff.kinetic_energy();
  Json w = Json::array(), p = Json::array();
  for (double c : ff.virial) w.push(c), p.push(c / ff.box.volume() * nktv2p);
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

void write_state(H5Writer& h5, const LammpsForceField& ff, const LammpsUnits& units) {
  const StyleUnits u = style_units(units.style);
  const double nktv2p = units.nktv2p;
  const std::string g = "/step_" + std::to_string(ff.steps_done);
  std::vector<double> ids(ff.id.begin(), ff.id.end());
  const std::vector<hsize_t> dims = {static_cast<hsize_t>(ff.size()), 3};
  write_quantity(h5, g + "/id", ids, "1");
  write_quantity(h5, g + "/position", ff.x, u.length, dims);
  write_quantity(h5, g + "/velocity", ff.v, u.velocity, dims);
  write_quantity(h5, g + "/angular_velocity", ff.omega, u.angular_velocity, dims);
  write_quantity(h5, g + "/force", ff.force, u.force, dims);
  write_quantity(h5, g + "/torque", ff.torque, u.torque, dims);
  std::vector<double> w(ff.virial.begin(), ff.virial.end()), p;
  for (double c : ff.virial) p.push_back(c / ff.box.volume() * nktv2p);
  write_quantity(h5, g + "/pair_virial", w, u.energy);
  write_quantity(h5, g + "/pair_pressure_tensor", p, u.pressure);
  h5.attribute(g, "contacts", static_cast<double>(ff.contacts));
  h5.attribute(g, "kinetic_energy", ff.kinetic_energy());
}

}  // namespace

void run_lammps_forces(const SceneFile& scene, const RunOptions& opts) {
  const std::string data_path = scene.input_path("lammps.data");
  const LammpsUnits units =
      scene.choice("lammps.units", "si", [](const std::string& s) { return lammps_units(s); });
  const std::string style = scene.text("lammps.pair_style");
  const std::vector<std::string> coeffs = scene.texts("lammps.pair_coeff");
  const double dt = scene.real("lammps.timestep");
  scene.require(dt > 0, "lammps.timestep", "must be positive");
  const long steps = scene.integer("run.steps", 0);
  scene.require(steps >= 0 && steps <= 1000000, "run.steps",
                "must lie in [0, 1e6]: this scene compares forces over a few steps");
  const long every = scene.integer("run.output_every", 0);
  scene.require(every >= 0, "run.output_every", "must not be negative (0: first and last step)");
  LammpsData data;
  try {
    data = read_lammps_data(data_path, 1.0, 1.0, 1.0);  // in the file's own units
  } catch (const InputError& e) {
    scene.require(false, "lammps.data", e.what());
  }
  LammpsPairModel model;
  try {
    model = parse_lammps_pair(style, coeffs, data.atom_types, units);
  } catch (const InputError& e) {
    scene.require(false, "lammps.pair_coeff", e.what());
  }
  std::unique_ptr<LammpsForceField> field;
  try {
    field = std::make_unique<LammpsForceField>(data, model, units, dt);
  } catch (const InputError& e) {
    scene.require(false, "lammps.data", e.what());
  }
  scene.reject_unknown_keys();
  if (!begin_outputs(opts)) return;
  LammpsForceField& ff = *field;

  SceneOutput output(scene, opts, "lammps_forces");
  H5Writer& h5 = output.h5();
  Json states = Json::array();
  auto record = [&] {
    check_finite(ff);
    write_state(h5, ff, units);
    states.push(state_json(ff, units.nktv2p));
    write_text_file(opts.out_dir + "/forces_step_" + std::to_string(ff.steps_done) + ".lammpstrj",
                    dump_text(ff));
    if (opts.progress)
      std::cerr << "lammps_forces: step " << ff.steps_done << " of " << steps << ", " << ff.contacts
                << " contacts\n";
  };
  // A refusal during the steps comes from where the atoms went: the time step moved them.
  auto stepped = [&](auto&& work) {
    try {
      work();
    } catch (const InputError& e) {
      throw PhysicsError(std::string(e.what()) + " at step " + std::to_string(ff.steps_done) +
                         ": lower lammps.timestep (" + scene.path() + ")");
    }
  };
  ff.compute(false);  // LAMMPS' setup: forces of the initial state, history not advanced
  record();
  for (long s = 1; s <= steps; ++s) {
    stepped([&] { ff.step(); });
    if (s == steps || (every > 0 && s % every == 0)) record();
  }
  h5.attribute("/", "atoms", static_cast<double>(ff.size()));
  h5.attribute("/", "volume", ff.box.volume());
  h5.attribute("/", "pair_style", model.describe());

  Json& summary = output.summary();
  Json choices = Json::object();
  choices["pair_style"] = model.describe();
  choices["box"] = data.triclinic() ? "triclinic" : "orthogonal";
  choices["conventions"] =
      "LAMMPS' own formulas (the version Debian 12 ships): gran/* styles take the contact point "
      "at the particle surfaces and project the shear history after advancing it; granular "
      "takes it mid-overlap and rotates the history with its length kept; no history update "
      "while a run sets up (step 0); fix nve/sphere integration. Contacts are found every "
      "step (no skin).";
  summary["choices"] = choices;
  summary["atoms"] = ff.size();
  summary["states"] = states;
  output.finish();
  std::cout << "lammps_forces: " << ff.size() << " atoms, " << model.describe() << ", " << steps
            << " steps; outputs in " << opts.out_dir << "\n";
}

}  // namespace granular
