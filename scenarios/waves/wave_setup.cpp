#include "scenarios/waves/wave_setup.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "scenarios/common/packing_file.hpp"

namespace granular {

namespace {

// The mixture of the materials and the walls' material.
void read_mixture(const SceneFile& s, WaveSetup& w, bool from) {
  if (!from) w.fractions = s.reals("mixture.volume_fractions");
  // The scene reader holds lists of numbers only: the materials are one comma-separated text.
  const std::string list = s.text("mixture.materials");
  size_t pos = 0;
  while (pos <= list.size()) {
    size_t end = list.find(',', pos);
    if (end == std::string::npos) end = list.size();
    std::string name = list.substr(pos, end - pos);
    while (!name.empty() && name.front() == ' ') name.erase(name.begin());
    while (!name.empty() && name.back() == ' ') name.pop_back();
    const auto it = w.mats.slot.find(name);
    s.require(it != w.mats.slot.end(), "mixture.materials",
              "names no material of [materials] (\"" + name + "\")");
    w.species.push_back(it->second);
    pos = end + 1;
  }
  if (!from) {
    s.require(w.species.size() == w.fractions.size(), "mixture.volume_fractions",
              "needs one fraction per material of mixture.materials");
    double sum = 0;
    for (double f : w.fractions) {
      s.require(f >= 0, "mixture.volume_fractions", "must not be negative");
      sum += f;
    }
    s.require(std::abs(sum - 1) < 1e-9, "mixture.volume_fractions", "must sum to 1");
  }
  for (int sp : w.species)
    s.require(w.mats.materials[sp].density > 0 && !w.mats.materials[sp].rigid(),
              "mixture.materials", "must name deformable materials with a positive density");
  w.wall = w.mats.at(s, "mixture.wall_material");
  s.require(w.mats.materials[w.wall].friction == 0, "mixture.wall_material",
            "must be frictionless (friction = 0): wall contacts start fresh in every run");
}

// The column: from a file, or a gas of these dimensions.
void read_column(const SceneFile& s, WaveSetup& w, bool from) {
  if (from) {
    column_from_file(s, w);
  } else {
    w.length = s.real("column.length");
    w.width = s.real("column.width");
    w.diameter = s.real("column.diameter");
    w.spread = s.real("column.spread", 0.05);
    w.gas_phi = s.real("column.gas_volume_fraction", 0.35);
    w.seed = s.integer("column.seed", 1);
    s.require(w.length >= 4, "column.length", "must be at least 4 diameters");
    s.require(w.width >= 3, "column.width", "must be at least 3 diameters (periodic images)");
    s.require(w.diameter > 0, "column.diameter", "must be positive");
    s.require(w.spread >= 0 && w.spread < 0.5, "column.spread", "must lie in [0, 0.5)");
    s.require(w.gas_phi > 0.05 && w.gas_phi < 0.45, "column.gas_volume_fraction",
              "must lie in (0.05, 0.45)");
  }
}

// The servo to each pressure, its relaxations and limits.
void read_preparation(const SceneFile& s, WaveSetup& w, bool from) {
  w.pressures = s.reals("preparation.pressures");
  s.require(!w.pressures.empty(), "preparation.pressures", "needs at least one pressure");
  for (size_t k = 0; k < w.pressures.size(); ++k)
    s.require(w.pressures[k] > 0 && (k == 0 || w.pressures[k] > w.pressures[k - 1]),
              "preparation.pressures", "must be positive and increasing (loading branch)");
  w.prep_friction = s.real("preparation.friction", 0.0);
  w.wall_speed = s.real("preparation.wall_speed");
  w.damping_time = s.real("preparation.damping_time");
  w.tolerance = s.real("preparation.tolerance", 0.02);
  w.relax_time = s.real("preparation.relax_time");
  w.max_time = s.real("preparation.max_time");
  w.gas_end_phi = s.real("preparation.gas_end_phi", 0.55);
  w.max_push = s.real("preparation.max_push", 0.003);
  w.final_relax_time = s.real("preparation.final_relax_time");
  const std::string unconverged = s.text("preparation.unconverged", "skip");
  s.require(unconverged == "skip" || unconverged == "stop", "preparation.unconverged",
            "must be \"skip\" or \"stop\"");
  w.stop_unconverged = unconverged == "stop";
  s.require(w.final_relax_time > 0, "preparation.final_relax_time", "must be positive");
  if (from)  // a file already denser than gas_end_phi skips the gas compression
    s.require(w.gas_end_phi > 0 && w.gas_end_phi < 0.64, "preparation.gas_end_phi",
              "must lie in (0, 0.64)");
  else
    s.require(w.gas_end_phi > w.gas_phi && w.gas_end_phi < 0.64, "preparation.gas_end_phi",
              "must lie between column.gas_volume_fraction and 0.64");
  s.require(w.max_push > 0 && w.max_push < 0.05, "preparation.max_push", "must lie in (0, 0.05)");
  s.require(w.prep_friction >= 0, "preparation.friction", "must not be negative");
  s.require(w.wall_speed > 0, "preparation.wall_speed", "must be positive");
  s.require(w.damping_time > 0 && w.damping_time < w.max_time, "preparation.damping_time",
            "must be positive and below preparation.max_time");
  s.require(w.tolerance > 0 && w.tolerance < 0.5, "preparation.tolerance", "must lie in (0, 0.5)");
  s.require(w.relax_time > 0, "preparation.relax_time", "must be positive");
  s.require(w.max_time > w.relax_time, "preparation.max_time", "must exceed relax_time");
}

// The pulse at the driven end and the recording after it.
void read_pulse(const SceneFile& s, WaveSetup& w) {
  w.shape = s.text("pulse.shape", "raised_cosine");
  s.require(w.shape == "raised_cosine" || w.shape == "ricker", "pulse.shape",
            "must be \"raised_cosine\" or \"ricker\"");
  w.duration = s.real("pulse.duration");
  w.velocity = s.real("pulse.velocity");
  w.amplitude_factors = s.reals("pulse.amplitude_factors", {1.0, 2.0});
  w.pre_time = s.real("pulse.pre_time");
  w.record_time = s.real("pulse.record_time");
  w.sample_every = s.integer("pulse.sample_every", 10);
  s.require(w.duration > 0, "pulse.duration", "must be positive");
  s.require(w.velocity > 0, "pulse.velocity", "must be positive");
  s.require(!w.amplitude_factors.empty() && w.amplitude_factors.front() == 1.0,
            "pulse.amplitude_factors", "must start with 1 (the reference amplitude)");
  for (double f : w.amplitude_factors)
    s.require(f > 0, "pulse.amplitude_factors", "must be positive");
  s.require(w.pre_time > 0, "pulse.pre_time", "must be positive (the pickers' noise window)");
  s.require(w.record_time > w.pre_time + w.duration, "pulse.record_time",
            "must exceed pre_time + duration");
  s.require(w.sample_every >= 1 && w.sample_every <= 1000000, "pulse.sample_every",
            "must lie in [1, 1e6] steps");
}

// Where the slabs of particles that pick the signal lie.
void read_receivers(const SceneFile& s, WaveSetup& w) {
  w.slab_positions = s.reals("receivers.slab_positions");
  w.slab_width = s.real("receivers.slab_width", 2.0);
  for (double x : w.slab_positions)
    s.require(x > 0 && x < 1, "receivers.slab_positions", "must lie in (0, 1) (fractions of L)");
  for (size_t k = 1; k < w.slab_positions.size(); ++k)
    s.require(w.slab_positions[k] > w.slab_positions[k - 1], "receivers.slab_positions",
              "must increase");
  s.require(w.slab_width > 0, "receivers.slab_width", "must be positive");
}

// The static strain probe of the modulus.
void read_probe(const SceneFile& s, WaveSetup& w) {
  w.probe_strain = s.real("probe.strain");
  w.probe_ramp = s.real("probe.ramp_time");
  w.probe_hold = s.real("probe.hold_time");
  w.probe_damping_time = s.real("probe.damping_time");
  s.require(w.probe_strain > 0 && w.probe_strain < 1e-3, "probe.strain", "must lie in (0, 1e-3)");
  s.require(w.probe_ramp > 0, "probe.ramp_time", "must be positive");
  s.require(w.probe_hold > 0, "probe.hold_time", "must be positive");
  s.require(w.probe_damping_time > 0, "probe.damping_time", "must be positive");
}

// The time step, the overlap limit, the step and restitution checks.
void read_run(const SceneFile& s, WaveSetup& w) {
  w.dt = s.real("run.dt");
  w.max_overlap = s.real("run.max_overlap", 0.05);
  w.dt_check = s.reals("run.dt_check", {});
  s.require(w.dt > 0, "run.dt", "must be positive");
  s.require(w.max_overlap > 0 && w.max_overlap < 0.5, "run.max_overlap", "must lie in (0, 0.5)");
  // Each phase at most 1e8 steps (hours on one core; the full scene's longest is 4e6): a
  // duration of 2^31 us ran for years.
  const std::pair<const char*, double> phases[] = {
      {"preparation.relax_time", w.relax_time},
      {"preparation.max_time", w.max_time},
      {"preparation.final_relax_time", w.final_relax_time},
      {"pulse.record_time", w.record_time},
      {"probe.ramp_time", w.probe_ramp},
      {"probe.hold_time", w.probe_hold},
      {"probe.damping_time", w.probe_damping_time}};
  for (const auto& [key, t] : phases)
    s.require(t / w.dt <= 1e8, key, "must be at most 1e8 time steps of run.dt");
  for (double f : w.dt_check)
    s.require(f >= 0.01 && f <= 1, "run.dt_check", "factors in [0.01, 1] (a run per factor)");
  w.restitution_check = s.reals("run.restitution_check", {});
  for (double e : w.restitution_check)
    s.require(e > 0 && e <= 1, "run.restitution_check", "restitutions in (0, 1]");
}

}  // namespace

WaveSetup read_wave_setup(const SceneFile& s) {
  WaveSetup w;
  w.mats = MaterialSet::read(s);
  const bool from = s.has("column.from");
  read_mixture(s, w, from);
  read_column(s, w, from);
  read_preparation(s, w, from);
  read_pulse(s, w);
  read_receivers(s, w);
  read_probe(s, w);
  read_run(s, w);
  w.signals = read_signal_settings(s, "analysis", w.pre_time);
  return w;
}

double pulse_velocity(const WaveSetup& w, double a, double t) {
  const double tau = t - w.pre_time;
  if (w.shape == "ricker") {  // centred at duration/2 with peak frequency 2/duration
    const double fp = 2.0 / w.duration, u = std::pow(M_PI * fp * (tau - 0.5 * w.duration), 2);
    return tau < 0 ? 0.0 : a * (1 - 2 * u) * std::exp(-u);
  }
  if (tau <= 0 || tau >= w.duration) return 0.0;
  return a * 0.5 * (1 - std::cos(2 * M_PI * tau / w.duration));
}

double pulse_displacement(const WaveSetup& w, double a, double t) {
  const double tau = t - w.pre_time, T = w.duration;
  if (tau <= 0) return 0.0;
  if (w.shape == "ricker") {  // d/dt [s exp(-(pi fp s)^2)] = (1 - 2u) exp(-u), s = tau - T/2
    const double fp = 2.0 / T, s = tau - 0.5 * T, s0 = -0.5 * T;
    return a * (s * std::exp(-std::pow(M_PI * fp * s, 2)) -
                s0 * std::exp(-std::pow(M_PI * fp * s0, 2)));
  }
  if (tau >= T) return a * 0.5 * T;
  return a * (0.5 * tau - T / (4 * M_PI) * std::sin(2 * M_PI * tau / T));
}

void column_from_file(const SceneFile& s, WaveSetup& w) {
  refuse_beside_packing(
      s,
      {"mixture.volume_fractions", "column.length", "column.width", "column.diameter",
       "column.spread", "column.gas_volume_fraction", "column.seed"},
      "column.from", "the particles, their sizes, box and mixture");
  const std::string path = s.input_path("column.from");
  const std::string group = s.text("column.from_group", "/final_state");
  PeriodicBox file_box;
  // The materials give the densities: 1 stands in for the density H5MD and state groups lack.
  HostParticles h = read_scene_packing(s, "column.from", path, 1.0, group, file_box);
  s.require(h.size() >= 16, "column.from", "holds fewer than 16 particles");
  const int kinds = static_cast<int>(w.species.size());
  double lo = INFINITY, hi = -INFINITY, dsum = 0, volume = 0;
  std::vector<double> by_species(kinds, 0.0);
  for (int i = 0; i < h.size(); ++i) {
    const int k = h.species[i];
    const double r = h.radius[i];
    s.require(k >= 0 && k < kinds, "mixture.materials",
              "names " + std::to_string(kinds) + " material(s), but particle " + std::to_string(i) +
                  " of " + path + " is of species " + std::to_string(k));
    s.require(r > 0 && std::isfinite(r) && std::isfinite(h.x[i]), "column.from",
              "particle " + std::to_string(i) + " has no positive radius or no position");
    h.species[i] = w.species[k];
    h.density[i] = w.mats.materials[w.species[k]].density;
    lo = std::min(lo, h.x[i] - r), hi = std::max(hi, h.x[i] + r);
    dsum += 2 * r;
    volume += r * r * r, by_species[k] += r * r * r;
  }
  w.diameter = dsum / h.size();
  PeriodicBox& box = w.from_box;
  box = PeriodicBox();
  box.len[0] = hi - lo, box.len[1] = file_box.len[1], box.len[2] = file_box.len[2];
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.periodic[d] = d != 0;
  for (int i = 0; i < h.size(); ++i)
    h.x[i] -= lo, h.y[i] -= file_box.lo[1], h.z[i] -= file_box.lo[2];
  w.length = box.len[0] / w.diameter;
  w.width = std::min(box.len[1], box.len[2]) / w.diameter;
  s.require(w.width >= 3, "column.from",
            "has a box narrower than 3 mean diameters across y or z (periodic images)");
  s.require(w.length >= 4, "column.from",
            "spans fewer than 4 mean diameters along x (the wave's direction)");
  w.fractions.clear();
  for (double v : by_species) w.fractions.push_back(v / volume);
  w.from = std::move(h);
}

}  // namespace granular
