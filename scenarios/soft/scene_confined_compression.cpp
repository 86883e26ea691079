// Scene `confined_compression`: soft polydisperse balls in a rigid box, compressed along z by the
// top wall and decompressed (docs/model_multicontact.md §5). Preparation: random insertion into a
// tall region, settling under gravity with background damping, the top wall closed at the box
// height. Then, from that one state, one run per force model (classical Hertz, MC-strain,
// MC-stress): force on the top wall against strain, the largest force and the wall-clock cost of
// each model on the same run. `fill.from` settles another tool's packing instead of the random
// insertion.
#include <Kokkos_Core.hpp>
#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/kernel_times.hpp"
#include "core/run/progress.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/box_fill.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/materials.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/packing_file.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/common/snapshot_series.hpp"
#include "scenarios/common/wall_config.hpp"
#include "scenarios/scene_registry.hpp"
#include "scenarios/soft/soft_models.hpp"

namespace granular {

namespace {

using Exec = Kokkos::DefaultExecutionSpace;

struct Setup {
  MaterialSet mats;
  int particle = 0, wall = 0;
  double size[3] = {165, 165, 167};
  FillSpec fill;
  HostParticles from_packing;  // fill.from: the particles to settle instead of a random insertion
  double region_height = 0, gravity = 0, damping_time = 0, settle_ratio = 0, settle_max_time = 0;
  double strain = 0, wall_speed = 0, dt = 0, max_overlap = 0.6;
  long sample_every = 100;
  long snapshot_every = 0;  // ParaView time series of each compression (0: none)
  double experiment_force = -1, experiment_strain = -1;
  std::vector<SoftModel> models;
};

// fill.from: another tool's packing (a LAMMPS data file, the last frame of an H5MD series, or
// a state group of an .h5 file, `fill.from_group`) settled in place of the random insertion.
// Its positions and radii are taken relative to its box's lower corner; every particle becomes
// compression.particle_material (density included), at rest. The file gives the particles,
// so the keys that would draw them are refused beside it.
void read_fill_packing(const SceneFile& s, const std::string& path, Setup& c) {
  refuse_beside_packing(s,
                        {"fill.count", "fill.diameter_mean", "fill.diameter_spread", "fill.seed"},
                        "fill.from", "the particles");
  const std::string group = s.text("fill.from_group", "/final_state");
  PeriodicBox file_box;
  HostParticles h = read_scene_packing(s, "fill.from", path, c.fill.density, group, file_box);
  s.require(h.size() <= 100000000, "fill.from", "holds more than 1e8 particles");
  double sum_d = 0;
  for (int i = 0; i < h.size(); ++i) {
    const double r = h.radius[i];
    h.x[i] -= file_box.lo[0], h.y[i] -= file_box.lo[1], h.z[i] -= file_box.lo[2];
    const bool inside = r > 0 && std::isfinite(r) && h.x[i] >= 0 && h.x[i] <= c.size[0] &&
                        h.y[i] >= 0 && h.y[i] <= c.size[1] && h.z[i] >= 0 &&
                        h.z[i] <= c.region_height;
    s.require(inside, "fill.from",
              "particle " + std::to_string(i) + " (centre " + std::to_string(h.x[i]) + ", " +
                  std::to_string(h.y[i]) + ", " + std::to_string(h.z[i]) + " mm, radius " +
                  std::to_string(r) +
                  " mm) lies outside the box (box.size across, fill.region_height high) or has "
                  "no positive radius");
    h.density[i] = c.fill.density, h.species[i] = c.particle;
    h.vx[i] = h.vy[i] = h.vz[i] = h.wx[i] = h.wy[i] = h.wz[i] = 0;
    sum_d += 2 * r;
  }
  c.fill.count = h.size();
  c.fill.diameter_mean = sum_d / h.size();
  c.from_packing = std::move(h);
}

Setup read_setup(const SceneFile& s) {
  Setup c;
  c.mats = MaterialSet::read(s);
  c.particle = c.mats.at(s, "compression.particle_material");
  c.wall = c.mats.at(s, "compression.wall_material");
  const auto size = s.reals("box.size");
  s.require(size.size() == 3 && size[0] > 0 && size[1] > 0 && size[2] > 0, "box.size",
            "must hold three positive lengths");
  for (int d = 0; d < 3; ++d) c.size[d] = size[d];
  c.fill.density = c.mats.materials[c.particle].density;
  c.fill.species = c.particle;
  c.region_height = s.real("fill.region_height");
  // Read only where given, so that the summaries of poured runs (every committed reference)
  // stay as they were.
  const std::string from = s.has("fill.from") ? s.input_path("fill.from") : std::string();
  if (from.empty()) {
    c.fill.count = s.count("fill.count", 1, kDemBytesPerParticle);
    c.fill.diameter_mean = s.real("fill.diameter_mean");
    c.fill.diameter_spread = s.real("fill.diameter_spread", 0.1);
    c.fill.seed = static_cast<std::uint64_t>(s.integer("fill.seed", 1));
  } else {
    read_fill_packing(s, from, c);
  }
  c.gravity = s.real("fill.gravity", 9.81e-9);  // mm/us^2
  c.damping_time = s.real("fill.damping_time");
  c.settle_ratio = s.real("fill.kinetic_energy_ratio", 1e-6);
  c.settle_max_time = s.real("fill.max_time");
  c.strain = s.real("compression.strain");
  c.wall_speed = s.real("compression.wall_speed");
  c.dt = s.real("compression.time_step");
  c.sample_every = s.integer("compression.sample_every", 100);
  c.max_overlap = s.real("run.max_overlap", 0.6);
  c.snapshot_every = s.integer("output.snapshot_every", 0);
  c.experiment_force = s.real("compression.experiment_max_force", -1.0);
  c.experiment_strain = s.real("compression.experiment_strain", -1.0);
  c.models = read_soft_models(s, c.mats);
  s.require(c.fill.diameter_mean > 0, "fill.diameter_mean", "must be positive");
  // The neighbour grid spans the box in cells of about a diameter: a box edge of 2^31 mm
  // asked for more cells than memory holds (std::bad_alloc).
  for (int d = 0; d < 3; ++d)
    s.require(c.size[d] <= 1000 * c.fill.diameter_mean, "box.size",
              "must be at most 1000 particle diameters (fill.diameter_mean) along each axis");
  s.require(c.fill.diameter_spread >= 0 && c.fill.diameter_spread < 1, "fill.diameter_spread",
            "must lie in [0, 1)");
  s.require(c.region_height >= c.size[2], "fill.region_height", "must reach the box height");
  s.require(c.gravity >= 0, "fill.gravity", "must not be negative");
  s.require(c.damping_time > 0, "fill.damping_time", "must be positive");
  s.require(c.settle_ratio > 0, "fill.kinetic_energy_ratio", "must be positive");
  s.require(c.settle_max_time > 0, "fill.max_time", "must be positive");
  s.require(c.gravity == 0 || 1.5 * std::sqrt(2 * c.region_height / c.gravity) < c.settle_max_time,
            "fill.max_time", "must exceed 1.5 free-fall times through fill.region_height");
  s.require(c.strain > 0 && c.strain < 0.6, "compression.strain", "must lie in (0, 0.6)");
  s.require(c.wall_speed > 0, "compression.wall_speed", "must be positive");
  s.require(c.dt > 0, "compression.time_step", "must be positive");
  s.require(c.sample_every >= 1, "compression.sample_every", "must be at least 1");
  s.require(c.snapshot_every >= 0, "output.snapshot_every", "must not be negative");
  s.require(c.fill.density > 0, "compression.particle_material", "needs a positive density");
  s.reject_unknown_keys();
  return c;
}

// Floor, four sides and the top wall (outward normals), the top at height `top`.
std::vector<WallSpec> box_walls(const Setup& c, double top) {
  const double n[6][3] = {{0, 0, -1}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, 1}};
  const double p[6][3] = {{0, 0, 0}, {0, 0, 0},         {c.size[0], 0, 0},
                          {0, 0, 0}, {0, c.size[1], 0}, {0, 0, top}};
  const char* names[6] = {"floor", "x_low", "x_high", "y_low", "y_high", "top"};
  std::vector<WallSpec> out;
  for (int w = 0; w < 6; ++w) {
    WallSpec s;
    s.name = names[w], s.material = c.wall;
    for (int d = 0; d < 3; ++d) s.normal[d] = n[w][d], s.point[d] = p[w][d];
    out.push_back(s);
  }
  return out;
}

PeriodicBox closed_box(const Setup& c, double height) {
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.periodic[d] = false;
  box.len[0] = c.size[0], box.len[1] = c.size[1], box.len[2] = height;
  return box;
}

// The poured packing and the settling system around it (walls set), as the preparation
// starts; `granular check` builds it too, so it applies the run's time-step guards.
struct Pour {
  HostParticles h;
  double mean_mass = 0, mean_d = 0;
};
Pour pour(const Setup& c) {
  PeriodicBox region_box = closed_box(c, c.region_height);
  FillSpec f = c.fill;
  for (int d = 0; d < 3; ++d) f.lo[d] = 0, f.hi[d] = d == 2 ? c.region_height : c.size[d];
  Pour p;
  p.h = c.from_packing.size() > 0 ? c.from_packing : fill_region(f, region_box);
  for (int i = 0; i < p.h.size(); ++i) {
    p.mean_mass += p.h.density[i] * 4.0 / 3.0 * M_PI * std::pow(p.h.radius[i], 3) / p.h.size();
    p.mean_d += 2 * p.h.radius[i] / p.h.size();
  }
  return p;
}
template <class Model>
DemSystem<Exec, Model> settling_system(const Model& model, const Setup& c, const Pour& p) {
  DemParams prm;
  prm.dt_key = "compression.time_step";
  prm.dt = c.dt, prm.skin = 0.1 * c.fill.diameter_mean, prm.max_overlap = c.max_overlap;
  prm.gravity[2] = -c.gravity;
  prm.damping.translational = p.mean_mass / c.damping_time;
  prm.damping.rotational = 0.1 * p.mean_mass * p.mean_d * p.mean_d / c.damping_time;
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(p.h), closed_box(c, c.region_height), model,
                             prm);
  sys.set_walls(box_walls(c, c.region_height));
  return sys;
}

// The settled packing the compressions start from (at rest), and the preparation's figures.
struct Preparation {
  ConfigState state;
  long settle_steps = 0;  // settling, closing the box and settling again
  double pile_height = 0, top_wall_force = 0, volume_fraction = 0;
  double wall_seconds = 0;
};

// Closes the box: the top wall comes down from the top of the insertion region to the box
// height at the compression speed (a pile standing higher is pressed down to it), then the
// packing settles again. Returns the steps it took.
template <class System, class Settled>
long close_box(System& sys, const Setup& c, const Settled& settled, long max_steps) {
  auto walls = box_walls(c, c.region_height);
  const double travel = c.region_height - c.size[2], t_now = sys.time();
  walls.back().motion = WallMotion::Table;
  walls.back().table_t = {t_now, t_now + travel / c.wall_speed + c.dt};
  walls.back().table_u = {0.0, -travel};
  sys.set_walls(walls);
  const long close_steps = static_cast<long>(std::ceil((travel / c.wall_speed + c.dt) / c.dt));
  sys.step(close_steps);
  sys.check_health(sys.measure());
  const long steps2 = settle(
      [&](long n) {
        sys.step(n);
        sys.check_health(sys.measure());
      },
      settled, 1000, max_steps);
  if (steps2 < 0)
    throw PhysicsError("the packing did not settle after closing the box within fill.max_time = " +
                       std::to_string(c.settle_max_time) + ": raise it");
  return close_steps + steps2;
}

template <class Model>
Preparation prepare(const Model& model, const Setup& c, const RunOptions& opts) {
  const Pour p = pour(c);
  const HostParticles& h = p.h;
  const double mean_mass = p.mean_mass, mean_d = p.mean_d;
  DemSystem<Exec, Model> sys = settling_system(model, c, p);
  // Settled: mean kinetic energy per particle below ratio x (mean weight x mean diameter).
  const double e_ref = mean_mass * std::max(c.gravity, 1e-300) * mean_d;
  const auto settled = [&]() { return sys.measure().ekin / h.size() < c.settle_ratio * e_ref; };
  const long max_steps = static_cast<long>(c.settle_max_time / c.dt);
  // Not settled before the highest particle could have landed: 1.5 free-fall times of the
  // region (the balls are inserted at rest, so the criterion holds at the start).
  const long fall_steps =
      c.gravity > 0
          ? static_cast<long>(std::ceil(1.5 * std::sqrt(2 * c.region_height / c.gravity) / c.dt))
          : 0;

  Progress progress("settling", max_steps, opts.progress);
  const long steps = settle(
      [&](long n) {
        sys.step(n);
        sys.check_health(sys.measure());
        progress.update(sys.steps());
      },
      settled, 1000, max_steps, fall_steps);
  progress.finish();
  if (steps < 0)
    throw PhysicsError("the poured packing did not settle within fill.max_time = " +
                       std::to_string(c.settle_max_time) +
                       ": raise it, or shorten fill.damping_time");
  Preparation prep;
  prep.settle_steps = steps + close_box(sys, c, settled, max_steps);
  std::vector<double> density(h.density);
  prep.state = snapshot(sys, density, 0.0);
  ConfigState& state = prep.state;
  for (int i = 0; i < state.size(); ++i)
    prep.pile_height = std::max(prep.pile_height, state.particles.z[i] + state.particles.radius[i]);
  prep.top_wall_force = sys.wall_loads().back().force[2];
  prep.volume_fraction = sys.particle_volume() / (c.size[0] * c.size[1] * c.size[2]);
  for (int i = 0; i < state.size(); ++i)  // start the compression from rest
    state.particles.vx[i] = state.particles.vy[i] = state.particles.vz[i] = 0;
  std::fill(state.w.begin(), state.w.end(), 0.0);
  return prep;
}

// The preparation under its kernel-timer phase, with its wall-clock time.
Preparation prepare_packing(const Setup& c, const RunOptions& opts) {
  Preparation prep;
  const auto t0 = std::chrono::steady_clock::now();
  {
    KernelRegion region("preparation");
    with_material_model(c.mats, [&](const auto& m) { prep = prepare(m, c, opts); });
  }
  prep.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return prep;
}

// The most compressed state of the first model's run: a copy of the particles (the system
// goes on moving its own), the box and the six walls as quads.
struct CompressedState {
  Particles<Exec> particles;
  PeriodicBox box;
  std::vector<double> quads;
};

template <class System>
CompressedState compressed_state(const System& sys) {
  const Particles<Exec>& p = sys.particles();
  CompressedState s;
  s.particles = Particles<Exec>(p.n);
  Particles<Exec>& q = s.particles;
  for (auto [to, from] : {std::pair(q.x, p.x), std::pair(q.v, p.v), std::pair(q.w, p.w),
                          std::pair(q.f, p.f), std::pair(q.torque, p.torque)})
    Kokkos::deep_copy(to, from);
  for (auto [to, from] :
       {std::pair(q.radius, p.radius), std::pair(q.mass, p.mass), std::pair(q.inertia, p.inertia)})
    Kokkos::deep_copy(to, from);
  Kokkos::deep_copy(q.species, p.species);
  Kokkos::deep_copy(q.id, p.id);
  s.box = sys.box();
  for (const auto& w : sys.walls().specs()) {
    double x[3], v[3];
    w.state(sys.time(), x, v);
    const auto quad = wall_quad(w.normal, x, sys.box());
    s.quads.insert(s.quads.end(), quad.begin(), quad.end());
  }
  return s;
}

struct Curve {
  std::vector<double> time, strain, force, position;
  double wall_seconds = 0, max_force = 0;
  long steps = 0;
  std::string failure;                        // why the run stopped early (empty: it finished)
  WallSeries walls;                           // every wall's position, force, torque and contacts
  std::optional<CompressedState> compressed;  // where kept and reached
};

// One sample of the walls: every wall's position, force, torque and contacts, and the top
// wall's position, strain and force (pushed up by the particles: positive).
template <class System>
void sample_walls(const System& sys, double H, Curve& out) {
  const auto loads = sys.wall_loads();
  const double z = sys.walls().host()(5).p[2];
  out.walls.time.push_back(sys.time());
  for (size_t w = 0; w < loads.size(); ++w) {
    for (int d = 0; d < 3; ++d) {
      out.walls.position[w].push_back(sys.walls().host()(w).p[d]);
      out.walls.force[w].push_back(loads[w].force[d]);
      out.walls.torque[w].push_back(loads[w].torque[d]);
    }
    out.walls.contacts[w].push_back(loads[w].contacts);
  }
  out.time.push_back(sys.time());
  out.position.push_back(z);
  out.strain.push_back((H - z) / H);
  out.force.push_back(loads[5].force[2]);
  out.max_force = std::max(out.max_force, loads[5].force[2]);
}

// One force model's compression and decompression from the settled packing; `keep_compressed`:
// the curve keeps the most compressed state.
template <class Model>
Curve compress(const Model& model, const MultiContact& mc, const Setup& c, const ConfigState& st,
               const std::string& label, const RunOptions& opts, bool keep_compressed) {
  DemParams prm;
  prm.dt_key = "compression.time_step";
  prm.dt = c.dt, prm.skin = 0.1 * c.fill.diameter_mean, prm.max_overlap = c.max_overlap;
  prm.gravity[2] = -c.gravity;
  const double H = c.size[2];
  DemSystem<Exec, Model> sys(particles_from<Exec>(st), closed_box(c, H), model, prm);
  restore_history(sys, st);  // the pair springs of the settled packing (walls start fresh)
  auto walls = box_walls(c, H);
  // Top wall: down by strain x H at the wall speed, then back up to H.
  const double travel = c.strain * H, t_half = travel / c.wall_speed;
  WallSpec& top = walls.back();
  top.motion = WallMotion::Table;
  top.table_t = {0.0, t_half, 2 * t_half};
  top.table_u = {0.0, -travel, 0.0};
  sys.set_walls(walls);
  if (mc.mode != MultiContact::None) sys.set_multicontact(mc);
  const long steps = static_cast<long>(std::ceil(2 * t_half / c.dt));
  Curve out;
  out.walls.resize(walls);
  Progress progress(label, steps, opts.progress);
  // Frames at the first sample at or after every k steps, one series per model.
  SnapshotSeries series(opts.out_dir, "snapshots_" + label, c.snapshot_every);
  // The kernel timer's phase spans exactly what wall_seconds times.
  std::optional<KernelRegion> region(std::in_place, "compression " + label);
  const auto t0 = std::chrono::steady_clock::now();
  sample_walls(sys, H, out);
  series.sample(sys);
  for (long s = 0; s < steps; s += c.sample_every) {
    sys.step(std::min(c.sample_every, steps - s));
    // A model that breaks down (MC-strain's explicit feedback at large loads) ends its own
    // curve, not the study: the curve up to there and the reason are kept.
    try {
      sys.check_health(sys.measure());
    } catch (const PhysicsError& e) {
      out.failure = e.what();
      break;
    }
    sample_walls(sys, H, out);
    series.sample(sys);
    progress.update(sys.steps());
    if (keep_compressed && !out.compressed && sys.time() >= t_half)
      out.compressed = compressed_state(sys);
  }
  out.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  region.reset();
  series.finish(sys);  // after the timing: the model's cost excludes the snapshot files
  out.steps = sys.steps();
  progress.finish();
  return out;
}

// The curve's lines on stdout.
void report_curve(const std::string& label, const Curve& curve) {
  std::cout << label << ": largest top-wall force " << curve.max_force << " N, "
            << curve.wall_seconds << " s wall clock (" << curve.steps << " steps)\n";
  if (!curve.failure.empty())
    std::cout << "  stopped at strain " << curve.strain.back() << ": " << curve.failure << "\n";
}

// One curve per force model of c.models, in order, each from the same settled packing; the
// first keeps its most compressed state.
std::vector<Curve> compress_all(const Setup& c, const ConfigState& state, const RunOptions& opts) {
  std::vector<Curve> curves;
  for (size_t k = 0; k < c.models.size(); ++k) {
    const SoftModel& sm = c.models[k];
    Curve curve;
    with_material_model(c.mats, [&](const auto& m) {
      curve = compress(m, sm.mc, c, state, sm.label, opts, k == 0);
    });
    report_curve(sm.label, curve);
    curves.push_back(std::move(curve));
  }
  return curves;
}

// A curve's series and attributes under /runs/<label> in results.h5; its figures for the summary.
Json write_curve(H5Writer& h5, const Setup& c, const std::string& label, const Curve& curve) {
  const std::string g = "/runs/" + label;
  write_quantity(h5, g + "/time", curve.time, "us");
  write_quantity(h5, g + "/strain", curve.strain, "1");
  write_quantity(h5, g + "/top_wall_force", curve.force, "N");
  write_quantity(h5, g + "/top_wall_position", curve.position, "mm");
  h5.attribute(g, "wall_seconds", curve.wall_seconds);
  curve.walls.write(h5, g + "/walls");
  Json j = Json::object();
  j["max_force"] = curve.max_force;
  j["wall_seconds"] = curve.wall_seconds;
  j["steps"] = curve.steps;
  j["particle_steps_per_second"] = curve.steps * c.fill.count / curve.wall_seconds;
  if (!curve.failure.empty()) {
    j["failure"] = curve.failure;
    j["failed_at_strain"] = curve.strain.back();
    j["failed_on_loading"] = curve.time.back() <= c.strain * c.size[2] / c.wall_speed;
    h5.attribute(g, "failure", curve.failure);
  }
  return j;
}

// results.h5 (the most compressed state, each curve, the study's constants) and its XDMF file
// of the compressed state, and summary.json (the preparation, each model, the experiment).
void write_study(SceneOutput& output, const RunOptions& opts, const Setup& c,
                 const Preparation& prep, const std::vector<Curve>& curves) {
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  Json jp = Json::object();
  jp["settle_steps"] = prep.settle_steps;
  jp["pile_height"] = prep.pile_height;
  jp["top_wall_force_at_start"] = prep.top_wall_force;
  jp["volume_fraction_box"] = prep.volume_fraction;
  jp["wall_seconds"] = prep.wall_seconds;
  summary["preparation"] = jp;
  Json models = Json::object();
  for (size_t k = 0; k < curves.size(); ++k) {
    if (const auto& s = curves[k].compressed) {
      write_state(h5, "/snapshot", s->particles, s->box, c.fill.density);
      write_quantity(h5, "/snapshot_walls/quads", s->quads, "mm",
                     {static_cast<hsize_t>(s->quads.size() / 3), 3});
    }
    models[c.models[k].label] = write_curve(h5, c, c.models[k].label, curves[k]);
  }
  summary["models"] = models;
  if (c.experiment_force > 0) {
    summary["experiment_max_force"] = c.experiment_force;
    summary["experiment_strain"] = c.experiment_strain;
  }
  h5.attribute("/", "strain", c.strain);
  h5.attribute("/", "experiment_max_force", c.experiment_force);
  h5.attribute("/", "experiment_strain", c.experiment_strain);
  output.commit_results();
  XdmfFrame scene_frame = state_frame("/snapshot", c.fill.count);  // with its six walls
  scene_frame.name = "scene", scene_frame.nwalls = 6;
  scene_frame.wall_dataset = "/snapshot_walls/quads";
  write_xdmf(opts.out_dir + "/compressed_state.xdmf", "results.h5", {scene_frame}, false);
}

}  // namespace

void run_confined_compression(const SceneFile& scene, const RunOptions& opts) {
  const Setup c = read_setup(scene);
  check_first_system(scene, opts, [&] {
    with_material_model(c.mats, [&](const auto& m) { settling_system(m, c, pour(c)); });
  });
  if (!begin_outputs(opts)) return;
  const Preparation prep = prepare_packing(c, opts);
  const std::vector<Curve> curves = compress_all(c, prep.state, opts);
  SceneOutput output(scene, opts, "confined_compression");
  write_study(output, opts, c, prep, curves);
  output.finish();
}

}  // namespace granular
