// The compiled part of the Python package `granular` (docs/python.md): the library API of
// scenarios/api/ and the scene registry, with NumPy arrays for particle data. The package's
// Python files (scenarios/python/granular/) add keyword arguments, the TOML text of the
// contact law and the run loop with a callback. Stepping releases the GIL.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Kokkos_Core.hpp>
#include <cstdlib>

#include "core/lammps/lammps_data.hpp"
#include "core/lammps/lammps_dump.hpp"
#include "core/run/error.hpp"
#include "scenarios/api/simulation.hpp"
#include "scenarios/common/run_report.hpp"
#include "scenarios/scene_registry.hpp"

namespace py = pybind11;
using namespace granular;
using granular::api::Packing;
using granular::api::Simulation;

namespace {

// Kokkos is started once per process, on first use or by initialize(threads).
void ensure_kokkos(int threads = 0) {
  if (Kokkos::is_initialized()) return;
  Kokkos::InitArguments args;
  args.num_threads = threads > 0 ? threads : -1;
  args.disable_warnings = true;
  Kokkos::initialize(args);
}

// Rows of n x k doubles as a NumPy array (a copy).
py::array_t<double> rows(const std::vector<double>& v, size_t k) {
  const size_t n = k ? v.size() / k : 0;
  py::array_t<double> a(k == 1 ? std::vector<size_t>{n} : std::vector<size_t>{n, k});
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}
py::array_t<double> xyz(const std::vector<double>& x, const std::vector<double>& y,
                        const std::vector<double>& z) {
  py::array_t<double> a({x.size(), size_t{3}});
  auto m = a.mutable_unchecked<2>();
  for (size_t i = 0; i < x.size(); ++i) m(i, 0) = x[i], m(i, 1) = y[i], m(i, 2) = z[i];
  return a;
}
void set_xyz(HostParticles& h, std::vector<double>& x, std::vector<double>& y,
             std::vector<double>& z,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& a,
             const char* name) {
  if (a.ndim() != 2 || a.shape(1) != 3 || a.shape(0) != h.size())
    throw InputError(std::string(name) + " must have shape (" + std::to_string(h.size()) + ", 3)");
  auto m = a.unchecked<2>();
  for (int i = 0; i < h.size(); ++i) x[i] = m(i, 0), y[i] = m(i, 1), z[i] = m(i, 2);
}
template <class T>
std::vector<T> column(const py::array_t<T, py::array::c_style | py::array::forcecast>& a, int n,
                      const char* name) {
  if (a.ndim() != 1 || a.shape(0) != n)
    throw InputError(std::string(name) + " must have shape (" + std::to_string(n) + ",)");
  return std::vector<T>(a.data(), a.data() + n);
}

py::dict measurements(const Measurements& m) {
  py::dict d;
  d["ekin"] = m.ekin, d["ekin_rot"] = m.ekin_rot, d["epot"] = m.epot;
  d["stress"] = std::vector<double>(m.stress, m.stress + 6);
  d["stress_normal"] = std::vector<double>(m.stress_normal, m.stress_normal + 6);
  d["stress_tangential"] = std::vector<double>(m.stress_tangential, m.stress_tangential + 6);
  d["fabric"] = std::vector<double>(m.fabric, m.fabric + 6);
  d["contact_histogram"] = std::vector<double>(m.contact_histogram, m.contact_histogram + 7);
  d["pressure"] = m.pressure, d["contacts"] = m.contacts, d["z"] = m.z;
  d["z_corrected"] = m.z_corrected, d["rattlers"] = m.rattlers, d["particles"] = m.particles;
  d["chi"] = m.chi, d["phi"] = m.phi, d["max_overlap"] = m.max_overlap, d["volume"] = m.volume;
  return d;
}

py::dict moduli(const Moduli& m) {
  py::dict d;
  d["K"] = m.K, d["G"] = m.G, d["M"] = m.M;
  d["K_n"] = m.K_n, d["K_t"] = m.K_t, d["G_n"] = m.G_n, d["G_t"] = m.G_t;
  d["eta_K"] = m.eta_K, d["eta_G"] = m.eta_G, d["eta_M"] = m.eta_M;
  return d;
}

DemParams dem_params(double dt, double skin, double damping, double rotational_damping,
                     int rattler_threshold, double max_overlap,
                     const std::array<double, 3>& gravity, const std::string& precision) {
  DemParams p;
  p.dt = dt;
  p.skin = skin;
  if (!(dt > 0)) throw InputError("dt must be positive");
  if (!(skin > 0)) throw InputError("skin must be positive (a length, mm)");
  p.dt_key = "dt";
  p.damping.translational = damping;
  p.damping.rotational = rotational_damping;
  p.rattler_threshold = rattler_threshold;
  p.max_overlap = max_overlap;
  for (int d = 0; d < 3; ++d) p.gravity[d] = gravity[d];
  if (precision != "double" && precision != "mixed")
    throw InputError(
        "precision must be \"double\" or \"mixed\" (fixed-point positions in the "
        "force pass, docs/mixed_precision.md), not \"" +
        precision + "\"");
  p.mixed_precision = precision == "mixed";
  return p;
}

WallSpec wall_from(const py::dict& d) {
  WallSpec w;
  for (auto item : d) {
    const std::string key = py::str(item.first);
    if (key == "name") {
      w.name = py::cast<std::string>(item.second);
    } else if (key == "normal" || key == "point" || key == "velocity") {
      const auto v = py::cast<std::array<double, 3>>(item.second);
      double* to = key == "normal" ? w.normal : key == "point" ? w.point : w.velocity;
      for (int k = 0; k < 3; ++k) to[k] = v[k];
    } else if (key == "material") {
      w.material = py::cast<int>(item.second);
    } else {
      throw InputError("wall: unknown key '" + key +
                       "' (known: name, normal, point, velocity, material)");
    }
  }
  if (w.velocity[0] != 0 || w.velocity[1] != 0 || w.velocity[2] != 0)
    w.motion = WallMotion::Velocity;
  return w;
}

// A LAMMPS dump frame of a simulation's particles, in SI (as `units si` decks and the data
// files of lammps_data_text) or in the engine's units.
std::string dump_of(const Simulation& s, bool si) {
  const HostParticles h = s.particles();
  const std::vector<double> f = s.forces();
  const PeriodicBox b = s.box();
  const double L = si ? 1e-3 : 1, V = si ? 1e3 : 1, W = si ? 1e6 : 1;  // mm, mm/us, 1/us
  LammpsDumpFrame d;
  d.step = s.steps();
  for (int k = 0; k < 3; ++k)
    d.lo[k] = b.lo[k] * L, d.len[k] = b.len[k] * L, d.periodic[k] = b.periodic[k];
  d.columns = {"id", "type",   "radius", "x",      "y",  "z",  "vx", "vy",
               "vz", "omegax", "omegay", "omegaz", "fx", "fy", "fz"};
  for (int i = 0; i < h.size(); ++i) {
    const double row[] = {i + 1.0,     h.species[i] + 1.0, h.radius[i] * L, h.x[i] * L,
                          h.y[i] * L,  h.z[i] * L,         h.vx[i] * V,     h.vy[i] * V,
                          h.vz[i] * V, h.wx[i] * W,        h.wy[i] * W,     h.wz[i] * W,
                          f[3 * i],    f[3 * i + 1],       f[3 * i + 2]};
    d.values.insert(d.values.end(), std::begin(row), std::end(row));
  }
  return lammps_dump_text(d);
}

// The engine's start and stop, and its errors as Python exceptions: a refused input is a
// ValueError, a run stopped by a guard a RuntimeError, each with the engine's message (which
// names the key and says what to change).
void bind_runtime(py::module_& m) {
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<PhysicsError>(m, "PhysicsError", PyExc_RuntimeError);
  m.def("initialize", &ensure_kokkos, py::arg("threads") = 0,
        "Start the engine with this many host threads (0: OMP_NUM_THREADS or all cores).");
  m.def("threads", [] {
    ensure_kokkos();
    return Kokkos::DefaultHostExecutionSpace().concurrency();
  });
  m.def("finalize", [] {
    if (Kokkos::is_initialized() && Simulation::alive() == 0) Kokkos::finalize();
  });
  m.def("backend", [] {
    ensure_kokkos();
    return std::string(Kokkos::DefaultExecutionSpace::name());
  });
}

// A Packing's particles: made from arrays, and each column read and set as an array.
void bind_packing_particles(py::class_<Packing>& cls) {
  cls.def(py::init([](py::array_t<double, py::array::c_style | py::array::forcecast> positions,
                      py::array_t<double, py::array::c_style | py::array::forcecast> radius,
                      py::array_t<double, py::array::c_style | py::array::forcecast> density,
                      std::array<double, 3> box_len, std::array<double, 3> box_lo) {
            Packing p;
            const int n = static_cast<int>(radius.size());
            p.particles.resize(n);
            set_xyz(p.particles, p.particles.x, p.particles.y, p.particles.z, positions,
                    "positions");
            p.particles.radius = column<double>(radius, n, "radius");
            p.particles.density = column<double>(density, n, "density");
            for (int d = 0; d < 3; ++d) p.box.len[d] = box_len[d], p.box.lo[d] = box_lo[d];
            return p;
          }),
          py::arg("positions"), py::arg("radius"), py::arg("density"), py::arg("box_len"),
          py::arg("box_lo") = std::array<double, 3>{0, 0, 0})
      .def_property_readonly("size", [](const Packing& p) { return p.particles.size(); })
      .def_property(
          "positions",
          [](const Packing& p) { return xyz(p.particles.x, p.particles.y, p.particles.z); },
          [](Packing& p, py::array_t<double, py::array::c_style | py::array::forcecast> a) {
            auto& h = p.particles;
            set_xyz(h, h.x, h.y, h.z, a, "positions");
          })
      .def_property(
          "velocities",
          [](const Packing& p) { return xyz(p.particles.vx, p.particles.vy, p.particles.vz); },
          [](Packing& p, py::array_t<double, py::array::c_style | py::array::forcecast> a) {
            auto& h = p.particles;
            set_xyz(h, h.vx, h.vy, h.vz, a, "velocities");
          })
      .def_property(
          "angular_velocities",
          [](const Packing& p) { return xyz(p.particles.wx, p.particles.wy, p.particles.wz); },
          [](Packing& p, py::array_t<double, py::array::c_style | py::array::forcecast> a) {
            auto& h = p.particles;
            set_xyz(h, h.wx, h.wy, h.wz, a, "angular_velocities");
          })
      .def_property(
          "radius", [](const Packing& p) { return rows(p.particles.radius, 1); },
          [](Packing& p, py::array_t<double, py::array::c_style | py::array::forcecast> a) {
            p.particles.radius = column<double>(a, p.particles.size(), "radius");
          })
      .def_property(
          "density", [](const Packing& p) { return rows(p.particles.density, 1); },
          [](Packing& p, py::array_t<double, py::array::c_style | py::array::forcecast> a) {
            p.particles.density = column<double>(a, p.particles.size(), "density");
          })
      .def_property(
          "species",
          [](const Packing& p) {
            return py::array_t<int>(p.particles.species.size(), p.particles.species.data());
          },
          [](Packing& p, py::array_t<int, py::array::c_style | py::array::forcecast> a) {
            p.particles.species = column<int>(a, p.particles.size(), "species");
          });
}

// A Packing's periodic box.
void bind_packing_box(py::class_<Packing>& cls) {
  cls.def_property(
         "box_len",
         [](const Packing& p) {
           return std::array<double, 3>{p.box.len[0], p.box.len[1], p.box.len[2]};
         },
         [](Packing& p, std::array<double, 3> v) {
           for (int d = 0; d < 3; ++d) p.box.len[d] = v[d];
         })
      .def_property(
          "box_lo",
          [](const Packing& p) {
            return std::array<double, 3>{p.box.lo[0], p.box.lo[1], p.box.lo[2]};
          },
          [](Packing& p, std::array<double, 3> v) {
            for (int d = 0; d < 3; ++d) p.box.lo[d] = v[d];
          })
      .def_property(
          "periodic",
          [](const Packing& p) {
            return std::array<bool, 3>{p.box.periodic[0], p.box.periodic[1], p.box.periodic[2]};
          },
          [](Packing& p, std::array<bool, 3> v) {
            for (int d = 0; d < 3; ++d) p.box.periodic[d] = v[d];
          });
}

// Packings from files and generators, saved states, and simulations made from either.
void bind_factories(py::module_& m) {
  m.def(
      "lammps_data_text",
      [](const Packing& p) { return lammps_data_text(p.particles, p.box.lo, p.box.len); },
      py::arg("packing"));
  m.def("random_packing", &api::random_packing, py::arg("count"), py::arg("diameter_min"),
        py::arg("diameter_max"), py::arg("density"), py::arg("phi"), py::arg("seed") = 1,
        py::arg("speed") = 0.0);
  m.def("read_lammps_packing", &api::read_lammps_packing, py::arg("path"));
  m.def("read_state_packing", &api::read_state_packing, py::arg("path"),
        py::arg("group") = "/final_state");

  py::class_<ConfigState>(m, "SavedState",
                          "A complete state: particles, box and every contact's history.")
      .def_property_readonly("size", &ConfigState::size)
      .def_readonly("phi", &ConfigState::phi)
      .def_readonly("pressure", &ConfigState::pressure)
      .def("write", [](const ConfigState& c, const std::string& path) { write_config(path, c); })
      .def_static("read", &read_config, py::arg("path"));

  auto make = [](auto build, double dt, double skin, double damping, double rotational_damping,
                 int rattler_threshold, double max_overlap, std::array<double, 3> gravity,
                 const std::string& precision) {
    ensure_kokkos();
    const DemParams p = dem_params(dt, skin, damping, rotational_damping, rattler_threshold,
                                   max_overlap, gravity, precision);
    return build(p);
  };
  m.def(
      "make_simulation",
      [make](const Packing& packing, const std::string& contact, const std::string& source,
             double dt, double skin, double damping, double rotational_damping,
             int rattler_threshold, double max_overlap, std::array<double, 3> gravity,
             const std::string& precision) {
        return make(
            [&](const DemParams& p) { return api::make_simulation(packing, contact, source, p); },
            dt, skin, damping, rotational_damping, rattler_threshold, max_overlap, gravity,
            precision);
      },
      py::arg("packing"), py::arg("contact"), py::arg("source"), py::arg("dt"), py::arg("skin"),
      py::arg("damping") = 0.0, py::arg("rotational_damping") = 0.0,
      py::arg("rattler_threshold") = 3, py::arg("max_overlap") = 0.3,
      py::arg("gravity") = std::array<double, 3>{0, 0, 0}, py::arg("precision") = "double");
  m.def(
      "restore_simulation",
      [make](const ConfigState& state, const std::string& contact, const std::string& source,
             double dt, double skin, double damping, double rotational_damping,
             int rattler_threshold, double max_overlap, std::array<double, 3> gravity,
             const std::string& precision) {
        return make(
            [&](const DemParams& p) { return api::restore_simulation(state, contact, source, p); },
            dt, skin, damping, rotational_damping, rattler_threshold, max_overlap, gravity,
            precision);
      },
      py::arg("state"), py::arg("contact"), py::arg("source"), py::arg("dt"), py::arg("skin"),
      py::arg("damping") = 0.0, py::arg("rotational_damping") = 0.0,
      py::arg("rattler_threshold") = 3, py::arg("max_overlap") = 0.3,
      py::arg("gravity") = std::array<double, 3>{0, 0, 0}, py::arg("precision") = "double");
}

using release = py::call_guard<py::gil_scoped_release>;

// A simulation's stepping and what it holds: time, box, measures, particles, contacts.
void bind_simulation_state(py::class_<Simulation>& cls) {
  cls.def("step", &Simulation::step, py::arg("n"), release())
      .def_property("strain_rate", &Simulation::strain_rate,
                    [](Simulation& s, std::array<double, 3> r) { s.set_strain_rate(r); })
      .def_property_readonly("time", &Simulation::time)
      .def_property_readonly("steps", &Simulation::steps)
      .def_property_readonly("size", &Simulation::size)
      .def_property_readonly("dt", [](const Simulation& s) { return s.params().dt; })
      .def_property_readonly("model", &Simulation::model_name)
      .def_property_readonly("mass", &Simulation::mass)
      .def_property_readonly("particle_volume", &Simulation::particle_volume)
      .def_property_readonly("box_len",
                             [](const Simulation& s) {
                               const PeriodicBox b = s.box();
                               return std::array<double, 3>{b.len[0], b.len[1], b.len[2]};
                             })
      .def_property_readonly("box_lo",
                             [](const Simulation& s) {
                               const PeriodicBox b = s.box();
                               return std::array<double, 3>{b.lo[0], b.lo[1], b.lo[2]};
                             })
      .def("measure", [](const Simulation& s) { return measurements(s.measure()); })
      .def("check_health", [](const Simulation& s) { s.check_health(s.measure()); })
      .def("packing",
           [](const Simulation& s) {
             Packing p;
             p.particles = s.particles();
             p.box = s.box();
             return p;
           })
      .def("forces", [](const Simulation& s) { return rows(s.forces(), 3); })
      .def("contacts", [](const Simulation& s) {
        const ContactNetwork c = s.contacts();
        py::dict d;
        d["i"] = py::array_t<int>(c.i.size(), c.i.data());
        d["j"] = py::array_t<int>(c.j.size(), c.j.data());
        d["branch"] = rows(c.branch, 3);
        d["normal_force"] = rows(c.normal_force, 1);
        d["tangential_force"] = rows(c.tangential_force, 3);
        d["overlap"] = rows(c.overlap, 1);
        return d;
      });
}

// The protocols a simulation runs: walls, compression, relaxation, the pressure servo, the
// moduli probe, and its dump, save and restart.
void bind_simulation_protocols(py::class_<Simulation>& cls) {
  cls.def("set_walls",
          [](Simulation& s, const py::list& walls) {
            std::vector<WallSpec> specs;
            for (auto w : walls) specs.push_back(wall_from(py::cast<py::dict>(w)));
            s.set_walls(specs);
          })
      .def("wall_loads",
           [](const Simulation& s) {
             py::list out;
             for (const WallLoad& l : s.wall_loads()) {
               py::dict d;
               d["force"] = std::vector<double>(l.force, l.force + 3);
               d["torque"] = std::vector<double>(l.torque, l.torque + 3);
               d["contacts"] = l.contacts, d["energy"] = l.energy;
               d["max_overlap"] = l.max_overlap;
               out.append(d);
             }
             return out;
           })
      .def("strain_to_phi", &Simulation::strain_to_phi, py::arg("phi"), py::arg("rate"),
           py::arg("every") = 500, release())
      .def("relax", &Simulation::relax, py::arg("ratio"), py::arg("max_steps"),
           py::arg("every") = 500, release())
      .def(
          "servo_to_pressure",
          [](Simulation& s, double target, double tolerance, double ekin_ratio, int max_cycles) {
            ServoSettings set;
            set.tolerance = tolerance, set.ekin_ratio = ekin_ratio, set.max_cycles = max_cycles;
            ServoResult r;
            {
              py::gil_scoped_release unlocked;
              r = s.servo_to_pressure(target, set);
            }
            py::dict d;
            d["converged"] = r.converged, d["cycles"] = r.cycles, d["steps"] = r.steps;
            d["ekin_ratio"] = r.ekin_ratio;
            d["measurements"] = measurements(r.m);
            return d;
          },
          py::arg("pressure"), py::arg("tolerance") = 0.02, py::arg("ekin_ratio") = 1e-6,
          py::arg("max_cycles") = 2000)
      .def(
          "probe_moduli",
          [](Simulation& s, double amplitude, long strain_steps, long relax_steps, bool restarting,
             int orientations) {
            if (orientations != 1 && orientations != 3)
              throw InputError("orientations must be 1 or 3");
            Moduli r;
            {
              py::gil_scoped_release unlocked;
              r = restarting ? s.probe_moduli_restarting(amplitude, strain_steps, relax_steps,
                                                         orientations)
                             : s.probe_moduli(amplitude, strain_steps, relax_steps);
            }
            return moduli(r);
          },
          py::arg("amplitude"), py::arg("strain_steps"), py::arg("relax_steps"),
          py::arg("restarting") = true, py::arg("orientations") = 1)
      .def("lammps_dump_text", &dump_of, py::arg("si") = true)
      .def("save", &Simulation::save)
      .def("restart", &Simulation::restart, py::arg("state"));
}

// The scene registry and the scene runner.
void bind_scenes(py::module_& m) {
  m.def("scenes", [] {
    py::dict d;
    for (const SceneEntry& e : scene_registry()) d[e.name] = e.description;
    return d;
  });
  m.def(
      "run_scene",
      [](const std::string& path, const std::string& out_dir, bool charts, bool progress,
         bool check_only) {
        ensure_kokkos();
        const SceneFile scene = SceneFile::load(path);
        const SceneEntry& entry = find_scene(scene);
        RunOptions opts;
        opts.out_dir = out_dir;
        opts.charts = charts;
        opts.progress = progress;
        opts.check_only = check_only;
        py::gil_scoped_release unlocked;
        if (check_only)
          entry.run(scene, opts);
        else
          run_scene(entry, scene, opts);
      },
      py::arg("path"), py::arg("out_dir"), py::arg("charts") = false, py::arg("progress") = false,
      py::arg("check_only") = false);
}

}  // namespace

PYBIND11_MODULE(_granular, m) {
  m.doc() = "granular: DEM of granular materials (compiled part; import granular instead)";
  bind_runtime(m);
  py::class_<Packing> packing(m, "Packing", "Particles and their periodic box, in identity order.");
  bind_packing_particles(packing);
  bind_packing_box(packing);
  bind_factories(m);
  py::class_<Simulation> simulation(m, "Simulation");
  bind_simulation_state(simulation);
  bind_simulation_protocols(simulation);
  bind_scenes(m);
}
