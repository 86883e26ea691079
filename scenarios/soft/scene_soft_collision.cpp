// Scene `soft_collision`: the multi-contact reference collisions (docs/model_multicontact.md §5).
// Three soft spheres in a row, the outer two launched at the centre one; five spheres (two more
// along y, launched the same way). For each material and each force model (classical Hertz,
// MC-strain, MC-stress): kinetic energy and the centre particle's overlap against time. A sphere
// pressed from several sides at once is where the models differ.
#include <Kokkos_Core.hpp>
#include <chrono>
#include <cmath>
#include <iostream>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/materials.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"
#include "scenarios/soft/soft_models.hpp"

namespace granular {

namespace {

struct Layout {
  std::string name;
  std::vector<std::array<double, 3>> dir;  // unit directions of the outer spheres
};

template <class Model>
Json run_one(const Model& model, const MultiContact& mc, const Layout& layout, int species,
             double density, double a, double speed, double dt, double duration, long every,
             H5Writer& h5, const std::string& group) {
  using Exec = Kokkos::DefaultExecutionSpace;
  const int n = 1 + static_cast<int>(layout.dir.size());
  const double start = 2 * a + 2 * speed * dt;  // touching after two steps
  HostParticles h;
  h.resize(n);
  for (int i = 0; i < n; ++i) h.radius[i] = a, h.density[i] = density, h.species[i] = species;
  for (int k = 0; k < n - 1; ++k) {
    const auto& d = layout.dir[k];
    h.x[k + 1] = start * d[0], h.y[k + 1] = start * d[1], h.z[k + 1] = start * d[2];
    h.vx[k + 1] = -speed * d[0], h.vy[k + 1] = -speed * d[1], h.vz[k + 1] = -speed * d[2];
  }
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = -8 * a, box.len[d] = 16 * a, box.periodic[d] = false;
  DemParams prm;
  // The source's rubber collisions at 10 m/s press classical Hertz to 0.89 a, and MC-strain's
  // pair law sees corrected overlaps of 1.21-1.25 a (measured; geometric at most 0.79 a): Hertz
  // far past its range, as in the source's runs. The limit sits above both; the time-step
  // guard evaluates the stiffness there.
  prm.dt = dt, prm.skin = 0.2 * a, prm.max_overlap = 1.3, prm.sort = false;
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
  if (mc.mode != MultiContact::None) sys.set_multicontact(mc);
  std::vector<double> t, ekin, overlap;
  auto xh = Kokkos::create_mirror_view(sys.particles().x);
  auto sample = [&]() {
    Kokkos::deep_copy(xh, sys.particles().x);
    double sum = 0;
    for (int k = 1; k < n; ++k) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (xh(k, d) - xh(0, d)) * (xh(k, d) - xh(0, d));
      sum += std::max(0.0, 2 * a - std::sqrt(r2));
    }
    t.push_back(sys.time());
    ekin.push_back(sys.measure().ekin);
    overlap.push_back(sum / (n - 1));
  };
  const auto t0 = std::chrono::steady_clock::now();
  sample();
  const long steps = static_cast<long>(duration / dt);
  // A model that breaks down (passes the overlap limit, or its forces stop being finite) ends
  // its own curve, not the scene: the curve up to there and the reason are kept, as in
  // confined_compression.
  std::string failure;
  for (long s = 0; s < steps; s += every) {
    try {
      sys.step(std::min(every, steps - s));
      sys.check_health(sys.measure());
    } catch (const PhysicsError& e) {
      failure = e.what();
      break;
    }
    sample();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_quantity(h5, group + "/time", t, "us");
  write_quantity(h5, group + "/kinetic_energy", ekin, "mJ");
  write_quantity(h5, group + "/centre_overlap", overlap, "mm");
  const double max_overlap = *std::max_element(overlap.begin(), overlap.end());
  Json j = Json::object();
  j["max_centre_overlap"] = max_overlap;
  j["max_centre_overlap_over_radius"] = max_overlap / a;
  j["kinetic_energy_final_over_initial"] = ekin.back() / ekin.front();
  j["wall_seconds"] = wall;
  if (!failure.empty()) {
    j["ended_early"] = failure;
    std::cerr << group << ": ended at t = " << t.back() << ": " << failure << "\n";
  }
  std::cout << group << ": largest centre overlap / a = " << max_overlap / a
            << ", final / initial kinetic energy " << ekin.back() / ekin.front() << " (" << wall
            << " s)\n";
  return j;
}

}  // namespace

void run_soft_collision(const SceneFile& scene, const RunOptions& opts) {
  const MaterialSet mats = MaterialSet::read(scene);
  const auto dts = scene.reals("soft.time_steps");
  for (double d : dts) scene.require(d > 0, "soft.time_steps", "must all be positive");
  scene.require(dts.size() == mats.materials.size(), "soft.time_steps",
                "needs one time step per material of [materials] (sorted by name)");
  const double a = 0.5 * scene.real("soft.diameter");
  const double speed = scene.real("soft.speed");
  const double duration = scene.real("soft.duration");
  const long every = scene.integer("soft.sample_every", 10);
  const auto models = read_soft_models(scene, mats);
  scene.require(a > 0, "soft.diameter", "must be positive");
  scene.require(speed > 0, "soft.speed", "must be positive");
  scene.require(duration > 0, "soft.duration", "must be positive");
  for (double d : dts)
    scene.require(duration / d <= 1e7, "soft.duration",
                  "takes more than 1e7 steps of soft.time_steps: shorten it");
  scene.require(every >= 1, "soft.sample_every", "must be at least 1");
  for (const auto& m : mats.materials)
    scene.require(m.density > 0, "materials." + m.name + ".density", "must be positive");
  scene.reject_unknown_keys();

  const std::vector<Layout> layouts = {{"three", {{1, 0, 0}, {-1, 0, 0}}},
                                       {"five", {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}}}};
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "soft_collision");
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  Json runs = Json::object();
  for (const Layout& layout : layouts)
    for (size_t s = 0; s < mats.materials.size(); ++s) {
      const Material& mat = mats.materials[s];
      const MaterialSet one = mats.only(static_cast<int>(s));  // species 0 in these runs
      for (const SoftModel& model : models) {
        const std::string group = "/runs/" + layout.name + "/" + mat.name + "/" + model.label;
        with_material_model(one, [&](const auto& m) {
          Json j = run_one(m, with_materials(model.mc, one), layout, 0, mat.density, a, speed,
                           dts[s], duration, every, h5, group);
          runs[layout.name + "/" + mat.name + "/" + model.label] = j;
        });
      }
    }
  summary["runs"] = runs;
  h5.attribute("/", "radius", a);
  output.finish();
}

}  // namespace granular
