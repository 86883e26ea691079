// Scene `wave_transmission`: virtual transducers (docs/model_mixtures_and_waves.md §3). A packing
// of one or more species between two frictionless walls along x, periodic in y and z, is brought by
// a servo on the source wall to each wall stress sigma_xx of a list (loading branch) and relaxed.
// From each relaxed state: a short velocity pulse of the source wall, recorded as the receiver
// wall's force and the mean x-velocity of particle slabs (pickers -> V_p, M = rho V_p^2, spectra,
// spectral-ratio Q between two slabs), repeated at other amplitudes (linearity check) and time
// steps; and a quasi-static uniaxial probe by the source wall, whose stress increment gives M
// directly for the same packing and boundary conditions.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/progress.hpp"
#include "core/run/rng.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/box_fill.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/common/snapshot_series.hpp"
#include "scenarios/scene_registry.hpp"
#include "scenarios/waves/skeleton.hpp"
#include "scenarios/waves/wave_setup.hpp"

namespace granular {

namespace {

using Exec = Kokkos::DefaultExecutionSpace;

// Source wall at x = xs (outward normal -x), receiver wall at x = box length (normal +x).
std::vector<WallSpec> column_walls(const WaveSetup& w, const PeriodicBox& box, double xs) {
  WallSpec src, rec;
  src.name = "source", rec.name = "receiver";
  src.material = rec.material = w.wall;
  src.normal[0] = -1, src.normal[1] = src.normal[2] = 0;
  rec.normal[0] = 1, rec.normal[1] = rec.normal[2] = 0;
  src.point[0] = xs;
  rec.point[0] = box.len[0];
  return {src, rec};
}

// sigma_xx from the two wall forces (particles push the source wall to -x, the receiver to +x).
double wall_stress(const std::vector<WallLoad>& loads, double area) {
  return 0.5 * (loads[1].force[0] - loads[0].force[0]) / area;
}

struct Prepared {
  ConfigState state;
  double xs = 0, pressure = 0, gap = 0, phi = 0, rho_bulk = 0, rho_solid = 0;
  double lateral_ratio = 0, z = 0, mean_overlap = 0, max_overlap = 0;
  long steps = 0;
  double target = 0;       // the servo's target sigma_xx
  bool converged = true;   // false: the servo ran out of preparation.max_time
  std::string servo_note;  // then: its last held states
};

// The column's gas: drawn (fill_region), or the packing file's particles (column.from).
HostParticles gas(const WaveSetup& w, PeriodicBox& box) {
  if (w.from) {
    box = w.from_box;
    return *w.from;
  }
  const double d = w.diameter;
  box = PeriodicBox();
  const double vol_p = M_PI / 6 * d * d * d * (1 + w.spread * w.spread);  // <d^3> of uniform
  box.len[1] = box.len[2] = w.width * d;
  box.len[0] = w.length * d;
  const int n =
      static_cast<int>(std::round(w.gas_phi * box.len[0] * box.len[1] * box.len[2] / vol_p));
  for (int k = 0; k < 3; ++k) box.lo[k] = 0, box.periodic[k] = k != 0;
  FillSpec f;
  f.count = n, f.diameter_mean = d, f.diameter_spread = w.spread, f.seed = w.seed;
  f.density = 1.0;
  for (int k = 0; k < 3; ++k) f.lo[k] = 0, f.hi[k] = box.len[k];
  HostParticles h = fill_region(f, box);
  // Species: exactly round(nu_s N) particles each (equal size distributions, so number and
  // volume fractions agree), assigned in the order of a random permutation of the particles.
  std::vector<std::pair<double, int>> order(n);
  for (int i = 0; i < n; ++i) order[i] = {Stream(w.seed + 7919, i).uniform(), i};
  std::sort(order.begin(), order.end());
  int next = 0;
  double cum = 0;
  for (size_t s = 0; s < w.species.size(); ++s) {
    cum += w.fractions[s];
    const int until = s + 1 == w.species.size() ? n : static_cast<int>(std::round(cum * n));
    for (; next < until; ++next) {
      const int i = order[next].second;
      h.species[i] = w.species[s];
      h.density[i] = w.mats.materials[w.species[s]].density;
    }
  }
  return h;
}

double mean_mass_of(const ConfigState& c) {
  double s = 0;
  for (int i = 0; i < c.size(); ++i)
    s += c.particles.density[i] * 4.0 / 3 * M_PI * std::pow(c.particles.radius[i], 3);
  return s / std::max(1, c.size());
}

DemParams params_of(const WaveSetup& w, double damping_time, double mass) {
  DemParams p;
  p.dt_key = "run.dt";
  p.dt = w.dt, p.skin = 0.05 * w.diameter, p.max_overlap = w.max_overlap;
  p.damping.translational = damping_time > 0 ? mass / damping_time : 0.0;
  p.damping.rotational =
      damping_time > 0 ? 0.1 * mass * w.diameter * w.diameter / damping_time : 0.0;
  return p;
}

// The particles' total mass (the servo's piston is given the sample's mass).
double sample_mass(const HostParticles& h) {
  double s = 0;
  for (int i = 0; i < h.size(); ++i) s += h.density[i] * 4.0 / 3 * M_PI * std::pow(h.radius[i], 3);
  return s;
}

// The gas the servo starts from, as a system (no walls yet); `granular check` builds it too.
template <class Model>
DemSystem<Exec, Model> servo_system(const Model& model, const WaveSetup& w, const HostParticles& h,
                                    const PeriodicBox& box) {
  return DemSystem<Exec, Model>(Particles<Exec>::from_host(h), box, model,
                                params_of(w, w.damping_time, sample_mass(h) / h.size()));
}

// The preparation's friction on the particles' materials.
MaterialSet preparation_materials(const WaveSetup& w) {
  MaterialSet m = w.mats;
  for (int sp : w.species) m.materials[sp].friction = w.prep_friction;
  return m;
}

// Loading branch: the servo drives the source wall until sigma_xx is within the tolerance
// of each target, then the packing relaxes with the wall held; a state is kept per target.
// One object per preparation: the system, the source wall's position and the stress it
// reads, and the phases of one target (gas compression, held states, piston).
template <class Model>
class WaveServo {
 public:
  WaveServo(const Model& model, const WaveSetup& w, const HostParticles& h, const PeriodicBox& box)
      : w_(w),
        box_(box),
        sys_(servo_system(model, w, h, box)),
        area_(box.len[1] * box.len[2]),
        sample_mass_(sample_mass(h)),
        max_steps_(static_cast<long>(w.max_time / w.dt)) {
    set_speed(0.0);
  }

  // Brings the packing to `target` and leaves the wall held there. Returns false where the
  // servo runs out of preparation.max_time (failure() then says how it ended); the wall is
  // held where it stopped.
  bool reach(double target, const RunOptions& opts) {
    Progress progress("servo to " + std::to_string(target) + " MPa", max_steps_, opts.progress);
    progress_ = &progress;
    target_ = target;
    steps_ = 0;
    sigma_ = wall_stress(sys_.wall_loads(), area_);
    held_.clear();
    failure_.clear();
    try {
      compress_gas();
      if (!held_states()) piston();
    } catch (const OutOfTime&) {
      failure_ = out_of_time_message();
    }
    set_speed(0.0);
    progress.finish();
    progress_ = nullptr;
    return failure_.empty();
  }
  const std::string& failure() const { return failure_; }

  DemSystem<Exec, Model>& system() { return sys_; }
  double wall_position() const { return xs_; }
  double stress() const { return sigma_; }
  long steps() const { return steps_; }
  double area() const { return area_; }

 private:
  // Source wall moving at v (into the sample) from now on.
  void set_speed(double v) {
    auto walls = column_walls(w_, box_, xs_);
    walls[0].motion = WallMotion::Velocity;
    walls[0].velocity[0] = v;
    walls[0].point[0] = xs_ - v * sys_.time();
    sys_.set_walls(walls);
  }

  bool on_target(double sigma) const { return std::abs(target_ - sigma) < w_.tolerance * target_; }

  void advance(double time) {
    const long n = std::max<long>(1, static_cast<long>(std::ceil(time / w_.dt)));
    sys_.step(n);
    steps_ += n;
    xs_ = sys_.walls().host()(0).p[0];
    sys_.check_health(sys_.measure());
    sigma_ = wall_stress(sys_.wall_loads(), area_);
    progress_->update(steps_);
    if (steps_ > max_steps_) throw OutOfTime{};
  }

  struct OutOfTime {};  // thrown by advance(), caught by reach()
  // The last held states say whether the servo oscillated, crept or never loaded.
  std::string out_of_time_message() const {
    std::ostringstream last;
    last.precision(6);
    const size_t from = held_.size() > 8 ? held_.size() - 8 : 0;
    for (size_t k = from; k < held_.size(); ++k)
      last << (k > from ? ", " : "") << "gap " << held_[k].first << " mm: " << held_[k].second;
    return "the servo did not reach sigma_xx = " + std::to_string(target_) +
           " MPa within preparation.max_time (now " + std::to_string(sigma_) + " MPa after " +
           std::to_string(held_.size()) + " held states; the last: " + last.str() +
           "): raise it, or preparation.wall_speed";
  }

  // A gas has no stiffness to aim with, and its wall force is a train of collisions: the
  // wall runs at wall_speed until the volume fraction reaches gas_end_phi, whatever the
  // force says.
  void compress_gas() {
    const double vp = sys_.particle_volume();
    while (vp / ((box_.len[0] - xs_) * area_) < w_.gas_end_phi) {
      set_speed(w_.wall_speed);
      advance(0.5 * w_.damping_time);
    }
  }

  // Held states: hold for relax_time, measure, and move the wall by 0.7 of the secant
  // estimate from the last two held states (a fixed small push while the packing carries no
  // load or the secant is not yet defined), at most max_push of the gap. A held state near
  // the target must stay there over final_relax_time. Returns false where it does not: the
  // packing creeps (see piston).
  bool held_states() {
    double x_prev = NAN, s_prev = NAN;
    while (true) {
      set_speed(0.0);
      advance(w_.relax_time);
      held_.emplace_back(box_.len[0] - xs_, sigma_);
      if (on_target(sigma_)) {
        advance(w_.final_relax_time);  // and still there after a long relaxation
        return on_target(sigma_);
      }
      const double gap = box_.len[0] - xs_, dmax = w_.max_push * gap;
      double dx = sigma_ > 0 ? 0.5 * dmax : dmax;
      const double slope =
          std::isfinite(s_prev) && xs_ != x_prev ? (sigma_ - s_prev) / (xs_ - x_prev) : 0;
      if (slope > 0 && sigma_ > 0)
        dx = 0.7 * (target_ - sigma_) / slope;
      else if (sigma_ > target_)
        dx = -0.5 * dmax;
      dx = std::clamp(dx, -dmax, dmax);
      x_prev = xs_, s_prev = sigma_;
      const double v = std::copysign(std::min(w_.wall_speed, std::abs(dx) / w_.damping_time), dx);
      set_speed(v);
      advance(dx / v);
    }
  }

  // Where a held state creeps, the stress read after relax_time was the push's transient,
  // and at a fixed wall it decays (in the full column at 0.05 MPa, from the target to 0.002
  // MPa over 1000 us) while the packing consolidates; held states then only inch towards
  // jamming. Here the wall is a piston of the sample's mass pushed by the target stress: it
  // follows the consolidation as it happens, and it comes to rest only where the packing
  // carries the target (the particles' damping takes the energy out). Each relax_time the
  // piston is judged like a held state, at rest.
  void piston() {
    const double tick = 0.1 * w_.damping_time;
    double vw = 0, peak = 0;
    while (true) {
      double moved = 0, mean = 0;
      const int ticks = std::max(1, static_cast<int>(std::lround(w_.relax_time / tick)));
      for (int k = 0; k < ticks; ++k) {
        vw += tick * (target_ - sigma_) * area_ / sample_mass_;
        set_speed(vw);
        const double x0 = xs_;
        advance(tick);
        moved += std::abs(xs_ - x0), mean += sigma_ / ticks;
      }
      held_.emplace_back(box_.len[0] - xs_, mean);
      // At rest: a piston that still travels carries a flow's drag, not a packing's load (a
      // steady creep at 6e-5 mm/us read as the target while the packing held 0.0025 MPa).
      peak = std::max(peak, moved);
      if (on_target(mean) && moved < 0.1 * peak) {
        set_speed(0.0), vw = 0;
        advance(w_.final_relax_time);
        if (on_target(sigma_)) return;
      }
    }
  }

  const WaveSetup& w_;
  const PeriodicBox& box_;
  DemSystem<Exec, Model> sys_;
  const double area_, sample_mass_;
  const long max_steps_;
  double xs_ = 0, sigma_ = 0, target_ = 0;
  long steps_ = 0;
  std::vector<std::pair<double, double>> held_;  // (gap, sigma_xx) of each held state
  Progress* progress_ = nullptr;
  std::string failure_;
};

// The state the servo holds at its target, with what the wave analysis needs of it.
template <class Model>
Prepared prepared_state(WaveServo<Model>& servo, const std::vector<double>& density,
                        const HostParticles& h, const PeriodicBox& box) {
  auto& sys = servo.system();
  const double area = servo.area(), sigma = servo.stress();
  Prepared p;
  p.xs = servo.wall_position(), p.pressure = sigma, p.steps = servo.steps();
  p.gap = box.len[0] - p.xs;
  const Measurements m = sys.measure();
  p.phi = sys.particle_volume() / (p.gap * area);
  double mass = 0, vol = 0;
  for (int i = 0; i < h.size(); ++i) {
    const double v = 4.0 / 3 * M_PI * std::pow(h.radius[i], 3);
    mass += density[i] * v, vol += v;
  }
  p.rho_bulk = mass / (p.gap * area);
  p.rho_solid = mass / vol;
  // measure() divides by the box volume, which includes the empty part behind the wall
  const double vbox = box.len[0] * area;
  p.lateral_ratio = 0.5 * (m.stress[1] + m.stress[2]) * vbox / (p.gap * area) / sigma;
  p.z = m.z, p.max_overlap = m.max_overlap;
  p.state = snapshot(sys, density, sigma);
  std::cout << "prepared sigma_xx = " << sigma << " MPa: phi = " << p.phi << ", Z = " << m.z
            << ", sigma_lat/sigma_xx = " << p.lateral_ratio << ", L = " << p.gap << " mm\n";
  return p;
}

template <class Model>
std::vector<Prepared> prepare(const Model& model, const WaveSetup& w,
                              const std::vector<double>& density, const HostParticles& h,
                              const PeriodicBox& box, const RunOptions& opts) {
  WaveServo<Model> servo(model, w, h, box);
  std::vector<Prepared> out;
  for (double target : w.pressures) {
    const bool converged = servo.reach(target, opts);
    if (!converged && w.stop_unconverged) throw PhysicsError(servo.failure());
    out.push_back(prepared_state(servo, density, h, box));
    out.back().target = target, out.back().converged = converged;
    if (!converged) {
      out.back().servo_note = servo.failure();
      std::cerr << servo.failure() << "; this state is left out of the analysis (listed in "
                << "summary.json's unconverged_states; preparation.unconverged = \"stop\" "
                << "stops the run instead)\n";
    }
  }
  return out;
}

struct WaveRecord {
  Trace source, force;         // source wall velocity, receiver wall force
  std::vector<Trace> slabs;    // mean x-velocity per slab
  std::vector<double> slab_x;  // slab centres, distance from the source wall
  double seconds = 0;
};

// The column's walls, the source wall driven by the pulse as a displacement table fine enough
// that its piecewise-constant velocity follows the shape (400 points over the pulse).
std::vector<WallSpec> pulse_walls(const WaveSetup& w, const PeriodicBox& box, double xs,
                                  double amplitude) {
  auto walls = column_walls(w, box, xs);
  WallSpec& s = walls[0];
  s.motion = WallMotion::Table;
  const int np = 400;
  const double t_end = w.pre_time + w.duration;
  s.table_t.push_back(0.0), s.table_u.push_back(0.0);
  for (int k = 0; k <= np; ++k) {
    const double t = w.pre_time + k * (t_end - w.pre_time) / np;
    s.table_t.push_back(t);
    s.table_u.push_back(-pulse_displacement(w, amplitude, t));  // along the outward normal
  }
  return walls;
}

// Slab membership by identity, fixed at the start (displacements are far below d): the
// identities in each receiver slab; the slabs' centres (distance from the source wall) go
// into r.slab_x.
template <class System>
std::vector<std::vector<int>> slab_members(const System& sys, const WaveSetup& w, const Prepared& p,
                                           WaveRecord& r) {
  std::vector<std::vector<int>> member(w.slab_positions.size());
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
  auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().id);
  for (size_t k = 0; k < w.slab_positions.size(); ++k) {
    const double c = p.xs + w.slab_positions[k] * p.gap, hw = 0.5 * w.slab_width * w.diameter;
    r.slab_x.push_back(c - p.xs);
    for (int i = 0; i < sys.particles().n; ++i)
      if (std::abs(x(i, 0) - c) <= hw) member[k].push_back(id(i));
    if (member[k].empty())
      throw InputError("receivers.slab_width: the slab at " + std::to_string(w.slab_positions[k]) +
                       " L holds no particle");
  }
  return member;
}

template <class Model>
WaveRecord transmit_raw(const Model& model, const WaveSetup& w, const Prepared& p,
                        const PeriodicBox& box, double amplitude, double dt,
                        SnapshotSeries* snapshots = nullptr) {
  WaveSetup wd = w;
  wd.dt = dt;
  DemSystem<Exec, Model> sys(particles_from<Exec>(p.state), box, model, params_of(wd, 0.0, 1.0));
  restore_history(sys, p.state);
  sys.set_walls(pulse_walls(w, box, p.xs, amplitude));
  const double area = box.len[1] * box.len[2];
  WaveRecord r;
  const std::vector<std::vector<int>> member = slab_members(sys, w, p, r);
  r.slabs.resize(member.size());
  std::vector<int> slab_of(sys.particles().n, -1);
  for (size_t k = 0; k < member.size(); ++k)
    for (int i : member[k]) slab_of[i] = static_cast<int>(k);
  auto vh = Kokkos::create_mirror_view(sys.particles().v);
  auto idh = Kokkos::create_mirror_view(sys.particles().id);
  auto sample = [&]() {
    const double t = sys.time();
    r.source.t.push_back(t), r.source.a.push_back(pulse_velocity(w, amplitude, t));
    r.force.t.push_back(t), r.force.a.push_back(sys.wall_loads()[1].force[0] / area);
    Kokkos::deep_copy(vh, sys.particles().v);
    Kokkos::deep_copy(idh, sys.particles().id);
    std::vector<double> sum(member.size(), 0.0);
    for (int i = 0; i < sys.particles().n; ++i)
      if (slab_of[idh(i)] >= 0) sum[slab_of[idh(i)]] += vh(i, 0);
    for (size_t k = 0; k < member.size(); ++k)
      r.slabs[k].t.push_back(t), r.slabs[k].a.push_back(sum[k] / member[k].size());
  };
  const long every = std::max<long>(1, static_cast<long>(std::round(w.sample_every * w.dt / dt)));
  const long steps = static_cast<long>(std::ceil(w.record_time / dt));
  const auto t0 = std::chrono::steady_clock::now();
  sample();
  if (snapshots) snapshots->sample(sys);
  for (long st = 0; st < steps; st += every) {
    sys.step(every);
    sample();
    if (snapshots) snapshots->sample(sys);
  }
  sys.check_health(sys.measure());
  if (snapshots) snapshots->finish(sys);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

// The pulse's signals: the run with the pulse minus the same run without it. A relaxed
// packing still moves (slow modes decay over many travel times), by as much as a linear-
// regime pulse; both runs are deterministic, so the difference is the pulse's own response.
template <class Model>
WaveRecord transmit(const Model& model, const WaveSetup& w, const Prepared& p,
                    const PeriodicBox& box, double amplitude, double dt,
                    SnapshotSeries* snapshots = nullptr) {
  WaveRecord r = transmit_raw(model, w, p, box, amplitude, dt, snapshots);
  const WaveRecord base = transmit_raw(model, w, p, box, 0.0, dt);
  for (int i = 0; i < r.force.size(); ++i) r.force.a[i] -= base.force.a[i];
  for (size_t k = 0; k < r.slabs.size(); ++k)
    for (int i = 0; i < r.slabs[k].size(); ++i) r.slabs[k].a[i] -= base.slabs[k].a[i];
  r.seconds += base.seconds;
  return r;
}

// Quasi-static uniaxial probe: sigma_xx after the source wall has moved in by strain x L
// (ramped, then held), minus sigma_xx of a run without strain of the same length.
template <class Model>
double probe_m(const Model& model, const WaveSetup& w, const Prepared& p, const PeriodicBox& box) {
  const double area = box.len[1] * box.len[2];
  double sigma[2] = {0, 0};
  for (int run = 0; run < 2; ++run) {
    DemSystem<Exec, Model> sys(particles_from<Exec>(p.state), box, model,
                               params_of(w, w.probe_damping_time, mean_mass_of(p.state)));
    restore_history(sys, p.state);
    auto walls = column_walls(w, box, p.xs);
    if (run == 1) {
      walls[0].motion = WallMotion::Table;
      walls[0].table_t = {0.0, w.probe_ramp};
      walls[0].table_u = {0.0, -w.probe_strain * p.gap};
    }
    sys.set_walls(walls);
    sys.step(static_cast<long>(std::ceil(w.probe_ramp / w.dt)));
    // average over the hold, sampled 20 times
    const long hold = static_cast<long>(std::ceil(w.probe_hold / w.dt));
    double acc = 0;
    for (int k = 0; k < 20; ++k) {
      sys.step(std::max<long>(1, hold / 20));
      acc += wall_stress(sys.wall_loads(), area) / 20;
    }
    sys.check_health(sys.measure());
    sigma[run] = acc;
  }
  return (sigma[1] - sigma[0]) / w.probe_strain;
}

}  // namespace

namespace {

const char* kPickers[3] = {"first_arrival", "first_peak", "first_trough"};

// The recorded signals: times in us; the source wall's velocity and the slabs' mean
// x-velocity in mm/us, the receiver wall's force per cross-section area in MPa.
const TraceUnits kVelocityTrace = {"us", "mm us-1"}, kStressTrace = {"us", "MPa"};

// A signal without a picked first event has no spectrum: an empty one, reported as such.
Spectrum safe_spectrum(const Trace& tr, const Picks& p, const SignalSettings& s) {
  try {
    return analyse_event(tr, p, s);
  } catch (const std::exception& e) {
    std::cerr << "warning: " << e.what() << "\n";
    return energy_spectrum({0.0, 0.0}, tr.step(), 2);
  }
}

// Travel times of one output against the input by each picker.
Json travel_times(const Picks& in, const Picks& out, double length, double rho, double* vp_peak) {
  Json j = Json::object();
  for (const char* k : kPickers) {
    const double t = picked_time(out, k) - picked_time(in, k);
    Json e = Json::object();
    e["travel_time"] = std::isfinite(t) ? Json(t) : Json();
    e["V_p"] = std::isfinite(t) && t > 0 ? Json(length / t) : Json();
    e["M"] = std::isfinite(t) && t > 0 ? Json(rho * length * length / (t * t)) : Json();
    if (vp_peak && std::string(k) == "first_peak") *vp_peak = length / t;
    j[k] = e;
  }
  return j;
}

// Travel times (source to receiver wall) and Q between the first and last slab of one run:
// one point of the time-step and damping checks.
Json numerics_entry(const WaveRecord& r, const WaveSetup& w, const Prepared& p) {
  const Picks po = pick_travel_times(r.force, w.signals.picker);
  const Picks pi = pick_travel_times(r.source, w.signals.picker);
  Json e = Json::object();
  e["travel"] = travel_times(pi, po, p.gap, p.rho_bulk, nullptr);
  e["wall_seconds"] = r.seconds;
  e["Q"] = Json();
  if (r.slabs.size() >= 2) {
    const size_t last = r.slabs.size() - 1;
    try {
      const Picks p0 = pick_travel_times(r.slabs[0], w.signals.picker);
      const Picks p1 = pick_travel_times(r.slabs[last], w.signals.picker);
      const SpectralRatioFit f = analyse_ratio(r.slabs[0], p0, r.slabs[last], p1, w.signals);
      if (std::isfinite(f.q)) e["Q"] = f.q;
      if (std::isfinite(f.q_error)) e["Q_error"] = f.q_error;
    } catch (const std::exception& ex) {
      e["Q"] = std::string("failed: ") + ex.what();
    }
  }
  return e;
}

}  // namespace

namespace {

// /table of results.h5: a row per state (NaN where a state was not analysed).
struct StateTable {
  std::vector<double> p, phi, rho, vp, mwave, mprobe, q, qerr, fdom;
  void add(const Prepared& s, double vp_peak, double m_wave, double m_probe, double q_slabs,
           double q_error, double f_mirrored) {
    p.push_back(s.pressure), phi.push_back(s.phi), rho.push_back(s.rho_bulk);
    vp.push_back(vp_peak), mwave.push_back(m_wave), mprobe.push_back(m_probe);
    q.push_back(q_slabs), qerr.push_back(q_error), fdom.push_back(f_mirrored);
  }
  void write(H5Writer& h5) const {
    write_quantity(h5, "/table/sigma_xx", p, "MPa");
    write_quantity(h5, "/table/phi", phi, "1");
    // rho_bulk: the particles' mass over the volume between the walls
    write_quantity(h5, "/table/rho_bulk", rho, "ug mm-3");
    write_quantity(h5, "/table/V_p_first_peak", vp, "mm us-1");
    write_quantity(h5, "/table/M_wave", mwave, "MPa");  // rho_bulk V_p^2
    write_quantity(h5, "/table/M_probe", mprobe, "MPa");
    write_quantity(h5, "/table/Q", q, "1");
    write_quantity(h5, "/table/Q_error", qerr, "1");
    write_quantity(h5, "/table/receiver_dominant_frequency_mirrored", fdom, "us-1");
  }
};

// A state the servo did not converge to: its summary row and its unconverged_states entry.
Json unconverged_row(const Prepared& p) {
  Json row = Json::object();
  row["servo_converged"] = false;
  row["target_sigma_xx"] = p.target;
  row["sigma_xx"] = p.pressure;
  row["gap"] = p.gap;
  row["phi"] = p.phi;
  row["z"] = p.z;
  row["preparation_steps"] = p.steps;
  return row;
}
Json unconverged_entry(size_t k, const Prepared& p) {
  Json e = Json::object();
  e["state"] = static_cast<double>(k);
  e["target_sigma_xx"] = p.target;
  e["sigma_xx"] = p.pressure;
  e["servo"] = p.servo_note;
  return e;
}

// The pulse at each amplitude (the first is the reference, recorded as snapshots where the
// scene asks): the reference run and its picks, and the amplitude check.
struct Pulses {
  Json amplitudes = Json::array();
  WaveRecord ref;
  Picks pin, pout;
  double vp_peak = NAN;
};
Pulses run_pulses(const WaveSetup& w, const Prepared& p, const PeriodicBox& box, size_t k,
                  const RunOptions& opts, long snapshot_every, bool with_contacts) {
  Pulses out;
  Json& amps = out.amplitudes;
  WaveRecord& ref = out.ref;
  Picks &pin = out.pin, &pout = out.pout;
  double& vp_peak = out.vp_peak;
  for (size_t a = 0; a < w.amplitude_factors.size(); ++a) {
    const double amp = w.velocity * w.amplitude_factors[a];
    WaveRecord r;
    SnapshotSeries snapshots(opts.out_dir, "snapshots_pressure_" + std::to_string(k),
                             a == 0 ? snapshot_every : 0);
    snapshots.record_contacts(with_contacts);
    with_material_model(w.mats,
                        [&](const auto& m) { r = transmit(m, w, p, box, amp, w.dt, &snapshots); });
    const Picks pi = pick_travel_times(r.source, w.signals.picker);
    const Picks po = pick_travel_times(r.force, w.signals.picker);
    Json e = Json::object();
    e["amplitude"] = amp;
    e["travel"] = travel_times(pi, po, p.gap, p.rho_bulk, a == 0 ? &vp_peak : nullptr);
    e["wall_seconds"] = r.seconds;
    if (a == 0) {
      ref = r, pin = pi, pout = po;
    } else {  // normalized receiver signals against the reference amplitude's
      double num = 0, den = 0;
      const double f = w.amplitude_factors[a];
      for (int i = 0; i < r.force.size() && i < ref.force.size(); ++i) {
        const double x = (r.force.a[i] - po.baseline) / f, y = ref.force.a[i] - pout.baseline;
        num = std::max(num, std::abs(x - y)), den = std::max(den, std::abs(y));
      }
      e["normalized_signal_max_difference"] = num / den;
      const double dtp = po.first_peak - pout.first_peak;
      e["first_peak_time_difference"] = std::isfinite(dtp) ? Json(dtp) : Json();
    }
    amps.push(e);
  }
  return out;
}

// What the reference pulse's signals say: the source's and the receiver's spectra (the
// receiver's also mirrored), each slab's picks and spectrum, and the spectral ratio between the
// first and the last slab.
struct SignalAnalysis {
  Spectrum source, receiver, mirrored;
  std::vector<Picks> slab_picks;
  std::vector<Spectrum> slab_spectra;
  std::optional<SpectralRatioFit> ratio;  // with two slabs or more, where the fit succeeds
  std::string ratio_failure;              // why it failed, where it did
};

SignalAnalysis analyse_signals(const WaveSetup& w, const Pulses& r) {
  const WaveRecord& ref = r.ref;
  SignalAnalysis a;
  a.source = safe_spectrum(ref.source, r.pin, w.signals);
  a.receiver = safe_spectrum(ref.force, r.pout, w.signals);
  // A one-signed first event has its largest |A| at f = 0; the spectrum of the signal up to
  // its first peak, mirrored to a full period (docs/model_mixtures_and_waves.md §4), has a
  // dominant frequency of its own: the receiver's rise time as a frequency.
  SignalSettings mirrored = w.signals;
  mirrored.spectrum.window = EventWindow::Mirrored;
  a.mirrored = safe_spectrum(ref.force, r.pout, mirrored);
  for (size_t s = 0; s < ref.slabs.size(); ++s) {
    a.slab_picks.push_back(pick_travel_times(ref.slabs[s], w.signals.picker));
    a.slab_spectra.push_back(safe_spectrum(ref.slabs[s], a.slab_picks[s], w.signals));
  }
  if (ref.slabs.size() >= 2) {
    const size_t last = ref.slabs.size() - 1;
    try {
      a.ratio = analyse_ratio(ref.slabs[0], a.slab_picks[0], ref.slabs[last], a.slab_picks[last],
                              w.signals);
    } catch (const std::exception& e) {
      a.ratio_failure = e.what();
    }
  }
  return a;
}

// Numerics: travel time and Q against the time step, and against contact damping (how much
// of Q is the contacts' dissipation rather than scattering), with the reference pulse's run
// in the same form for the charts.
struct Numerics {
  Json dt_check = Json::array(), restitution_check = Json::array(), reference;
};

Json reference_numerics(const WaveSetup& w, const Prepared& p, const WaveRecord& ref) {
  Json e = numerics_entry(ref, w, p);
  e["dt"] = w.dt;
  // Its restitution, when every material has the same one (a point of the damping check).
  bool uniform = true;
  for (const auto& mat : w.mats.materials)
    uniform = uniform && mat.restitution == w.mats.materials[0].restitution;
  e["restitution"] = uniform ? Json(w.mats.materials[0].restitution) : Json();
  return e;
}

Numerics numerics_checks(const WaveSetup& w, const Prepared& p, const PeriodicBox& box,
                         const WaveRecord& ref) {
  Numerics n;
  for (double fct : w.dt_check) {
    WaveRecord r;
    with_material_model(w.mats,
                        [&](const auto& m) { r = transmit(m, w, p, box, w.velocity, w.dt * fct); });
    Json e = numerics_entry(r, w, p);
    e["dt"] = w.dt * fct;
    n.dt_check.push(e);
  }
  for (double e_r : w.restitution_check) {
    MaterialSet mats = w.mats;
    for (auto& mat : mats.materials) mat.restitution = e_r;
    WaveRecord r;
    with_material_model(mats, [&](const auto& m) { r = transmit(m, w, p, box, w.velocity, w.dt); });
    Json e = numerics_entry(r, w, p);
    e["restitution"] = e_r;
    n.restitution_check.push(e);
  }
  n.reference = reference_numerics(w, p, ref);
  return n;
}

// ParaView time series of the reference pulse at each pressure (output.snapshot_every, 0:
// none): frames at the first receiver sample at or after every k steps.
struct SnapshotChoice {
  long every = 0;
  bool contacts = false;
};

// One prepared state probed: the static probe's modulus, the pulses, what their signals say,
// the numerics checks, and the measures derived from them.
struct ProbedState {
  double m_probe = 0;
  Pulses pulses;
  SignalAnalysis signals;
  Numerics numerics;
  double m_wave = NAN;            // rho_bulk V_p^2, V_p by the first peak
  double q = NAN, q_error = NAN;  // between the first and the last slab
  // The pulse runs through the load-bearing skeleton, whose density is rho_bulk (1 - f), f
  // the mass fraction of rattlers peeled below 2 contacts (skeleton.hpp: without gravity a
  // particle with one contact carries no load). Peeling below 4 takes every particle of
  // these frictional packings (Z = 4.1-4.3), so 4 is no criterion here.
  double f_rattlers = 0;
};

ProbedState probe_state(const WaveSetup& w, const Prepared& p, const PeriodicBox& box, size_t k,
                        const RunOptions& opts, const SnapshotChoice& snap) {
  ProbedState s;
  with_material_model(w.mats, [&](const auto& m) { s.m_probe = probe_m(m, w, p, box); });
  s.pulses = run_pulses(w, p, box, k, opts, snap.every, snap.contacts);
  s.signals = analyse_signals(w, s.pulses);
  if (s.signals.ratio) s.q = s.signals.ratio->q, s.q_error = s.signals.ratio->q_error;
  s.numerics = numerics_checks(w, p, box, s.pulses.ref);
  s.m_wave = p.rho_bulk * s.pulses.vp_peak * s.pulses.vp_peak;
  s.f_rattlers = rattler_mass_fraction(p.state, p.xs, box.len[0], 2);
  std::cout << "sigma_xx = " << p.pressure << " MPa: V_p (first peak) = " << s.pulses.vp_peak
            << " mm/us, M_wave = " << s.m_wave << " MPa, M_probe = " << s.m_probe
            << " MPa, Q = " << s.q << "\n";
  return s;
}

// Every state the servo reached probed, in order; a state it did not reach is not (no probe,
// no pulse: its entry is empty).
std::vector<std::optional<ProbedState>> probe_states(const WaveSetup& w,
                                                     const std::vector<Prepared>& states,
                                                     const PeriodicBox& box, const RunOptions& opts,
                                                     const SnapshotChoice& snap) {
  std::vector<std::optional<ProbedState>> probed;
  for (size_t k = 0; k < states.size(); ++k) {
    probed.emplace_back();
    if (states[k].converged) probed.back() = probe_state(w, states[k], box, k, opts, snap);
  }
  return probed;
}

// The slabs' part of a state's row: each slab's picks, travel times and spectrum; with two
// slabs or more, V_p between the first and the last by each picker, and their spectral ratio.
void add_slab_rows(Json& row, const Prepared& p, const ProbedState& s) {
  const WaveRecord& ref = s.pulses.ref;
  const SignalAnalysis& a = s.signals;
  Json slabs = Json::array();
  for (size_t k = 0; k < ref.slabs.size(); ++k) {
    Json sj = Json::object();
    sj["distance"] = ref.slab_x[k];
    sj["picks"] = picks_json(a.slab_picks[k]);
    sj["travel"] = travel_times(s.pulses.pin, a.slab_picks[k], ref.slab_x[k], p.rho_bulk, nullptr);
    sj["spectrum"] = spectrum_json(a.slab_spectra[k]);
    slabs.push(sj);
  }
  row["slabs"] = slabs;
  if (ref.slabs.size() < 2) return;
  const size_t last = ref.slabs.size() - 1;
  Json between = Json::object();  // no wall in the path
  for (const char* pk : kPickers) {
    const double dtp = picked_time(a.slab_picks[last], pk) - picked_time(a.slab_picks[0], pk);
    const double dx = ref.slab_x[last] - ref.slab_x[0];
    between[pk] = std::isfinite(dtp) && dtp > 0 ? Json(dx / dtp) : Json();
  }
  row["V_p_between_slabs"] = between;
  row["spectral_ratio"] = a.ratio ? ratio_json(*a.ratio) : Json("failed: " + a.ratio_failure);
}

// A probed state's row of the summary's table.
Json probed_row(const Prepared& p, const ProbedState& s) {
  Json row = Json::object();
  row["sigma_xx"] = p.pressure;
  row["gap"] = p.gap;
  row["phi"] = p.phi;
  row["rho_bulk"] = p.rho_bulk;
  row["rho_solid"] = p.rho_solid;
  row["lateral_stress_ratio"] = p.lateral_ratio;
  row["z"] = p.z;
  row["max_overlap"] = p.max_overlap;
  row["preparation_steps"] = p.steps;
  row["M_probe"] = s.m_probe;
  row["amplitudes"] = s.pulses.amplitudes;
  row["travel"] = travel_times(s.pulses.pin, s.pulses.pout, p.gap, p.rho_bulk, nullptr);
  row["receiver_spectrum"] = spectrum_json(s.signals.receiver);
  row["receiver_spectrum_mirrored"] = spectrum_json(s.signals.mirrored);
  add_slab_rows(row, p, s);
  row["dt_check"] = s.numerics.dt_check;
  row["restitution_check"] = s.numerics.restitution_check;
  row["reference_numerics"] = s.numerics.reference;
  // No first peak (a run too short for the pulse to arrive): null, not NaN, in the JSON.
  const bool arrived = std::isfinite(s.m_wave);
  row["M_wave_first_peak"] = arrived ? Json(s.m_wave) : Json();
  row["M_wave_over_M_probe"] = arrived ? Json(s.m_wave / s.m_probe) : Json();
  Json skeleton = Json::object();
  skeleton["rattler_mass_fraction"] = s.f_rattlers;
  skeleton["M_wave_over_M_probe"] =
      arrived ? Json(s.m_wave * (1 - s.f_rattlers) / s.m_probe) : Json();
  row["skeleton"] = skeleton;
  return row;
}

// A probed state's signals, spectra and spectral ratio into its group g of results.h5.
void write_state_signals(H5Writer& h5, const std::string& g, const Prepared& p,
                         const ProbedState& s) {
  const WaveRecord& ref = s.pulses.ref;
  const SignalAnalysis& a = s.signals;
  write_signal(h5, g + "/source", ref.source, s.pulses.pin, a.source, kVelocityTrace);
  write_signal(h5, g + "/receiver", ref.force, s.pulses.pout, a.receiver, kStressTrace);
  write_quantity(h5, g + "/receiver_mirrored/frequency", a.mirrored.f,
                 frequency_unit(kStressTrace));
  write_quantity(h5, g + "/receiver_mirrored/energy", a.mirrored.energy, energy_unit(kStressTrace));
  for (size_t k = 0; k < ref.slabs.size(); ++k) {
    const std::string slab = g + "/slab_" + std::to_string(k);
    write_signal(h5, slab, ref.slabs[k], a.slab_picks[k], a.slab_spectra[k], kVelocityTrace);
    h5.attribute(slab, "distance", ref.slab_x[k]);
  }
  if (a.ratio) {
    write_quantity(h5, g + "/ratio/frequency", a.ratio->f, frequency_unit(kVelocityTrace));
    write_quantity(h5, g + "/ratio/log_ratio", a.ratio->log_ratio, "1");  // ln(A2/A1)
    h5.attribute(g + "/ratio", "slope", a.ratio->slope);
    h5.attribute(g + "/ratio", "intercept", a.ratio->intercept);
  }
  h5.attribute(g, "sigma_xx", p.pressure);
  h5.attribute(g, "gap", p.gap);
}

// What the summary says of the column as a whole.
void describe_column(Json& summary, const WaveSetup& w, const HostParticles& h) {
  summary["particles"] = h.size();
  summary["density_in_M"] = "packing density: total particle mass / volume between the walls";
  summary["pair_rule"] = w.mats.pair_rule;
  if (w.from) {  // only then, so that the summaries of drawn columns stay as they were
    summary["start"] = "the packing file of column.from, walls at its particles' extent along x";
    Json fr = Json::object();
    for (size_t k = 0; k < w.species.size(); ++k)
      fr[w.mats.materials[w.species[k]].name] = w.fractions[k];
    summary["volume_fractions_of_file"] = fr;
    summary["column_length_diameters"] = w.length;
  }
}

// The study into results.h5 (a group per probed state, then the table) and summary.json (a
// row per state, the states the servo did not reach).
void write_study(SceneOutput& output, const WaveSetup& w, const HostParticles& h,
                 const std::vector<Prepared>& states,
                 const std::vector<std::optional<ProbedState>>& probed) {
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  describe_column(summary, w, h);
  Json table = Json::array(), unconverged = Json::array();
  StateTable columns;
  for (size_t k = 0; k < states.size(); ++k) {
    const Prepared& p = states[k];
    if (const auto& s = probed[k]) {
      table.push(probed_row(p, *s));
      write_state_signals(h5, "/pressure_" + std::to_string(k), p, *s);
      columns.add(p, s->pulses.vp_peak, s->m_wave, s->m_probe, s->q, s->q_error,
                  s->signals.mirrored.dominant_frequency);
      continue;
    }
    // Not probed, no pulse: its row says where the servo stopped.
    table.push(unconverged_row(p));
    unconverged.push(unconverged_entry(k, p));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    columns.add(p, nan, nan, nan, nan, nan, nan);
  }
  summary["states"] = table;
  // Targets the servo did not reach within preparation.max_time (preparation.unconverged).
  summary["unconverged_states"] = unconverged;
  columns.write(h5);
  h5.attribute("/", "states", static_cast<double>(states.size()));
}

SnapshotChoice read_snapshot_choice(const SceneFile& scene) {
  SnapshotChoice snap;
  snap.every = scene.integer("output.snapshot_every", 0);
  scene.require(snap.every >= 0, "output.snapshot_every", "must not be negative");
  snap.contacts = snapshot_contacts(scene);
  scene.require(!snap.contacts || snap.every > 0, "output.snapshot_contacts",
                "needs output.snapshot_every > 0 (the frames it adds the network to)");
  return snap;
}

// The first system the run would build (the gas in the servo's box, its walls' contacts
// guarded too) checked before any output is touched.
void check_column(const SceneFile& scene, const RunOptions& opts, const WaveSetup& w) {
  check_first_system(scene, opts, [&] {
    PeriodicBox b;
    const HostParticles g = gas(w, b);
    with_material_model(preparation_materials(w), [&](const auto& m) {
      auto sys = servo_system(m, w, g, b);
      sys.set_walls(column_walls(w, b, 0.0));
    });
  });
}

}  // namespace

void run_wave_transmission(const SceneFile& scene, const RunOptions& opts) {
  const WaveSetup w = read_wave_setup(scene);
  const SnapshotChoice snap = read_snapshot_choice(scene);
  scene.reject_unknown_keys();
  check_column(scene, opts, w);
  if (!begin_outputs(opts)) return;
  const auto wall0 = std::chrono::steady_clock::now();
  PeriodicBox box;
  const HostParticles h = gas(w, box);
  std::vector<Prepared> states;
  with_material_model(preparation_materials(w),
                      [&](const auto& m) { states = prepare(m, w, h.density, h, box, opts); });
  const auto probed = probe_states(w, states, box, opts, snap);
  SceneOutput output(scene, opts, "wave_transmission");
  write_study(output, w, h, states, probed);
  output.summary()["wall_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  output.finish();
}

}  // namespace granular
