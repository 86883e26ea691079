// One impact, measured the way DEM codes are verified: a sphere hits a wall or a second
// sphere at rest, at any incidence angle and with any initial spin. The contact normal is
// z (the wall is the plane z = 0 below the sphere; the target sphere sits at the origin);
// the plane of incidence is xz. Shared by the `impact` scene and the tests.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/dem/walls.hpp"
#include "core/run/finite.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/snapshot_series.hpp"

namespace granular {

struct ImpactSetup {
  bool wall = true;  // target: a fixed wall (material slot wall_material) or a sphere at rest
  int wall_material = 1;
  double radius1 = 1.0, density1 = 1.0;  // the moving sphere
  int species1 = 0;
  double radius2 = 1.0, density2 = 1.0;  // the target sphere
  int species2 = 0;
  double speed = 1.0;  // impact speed
  double angle = 0.0;  // incidence angle from the normal (radians): v = speed (sin, 0, -cos)
  double spin[3] = {0, 0, 0};  // initial angular velocity of the moving sphere
  // The target sphere's own motion (not with a wall); `speed` and `angle` then give the
  // velocity of the moving sphere relative to it.
  double target_velocity[3] = {0, 0, 0};
  double target_spin[3] = {0, 0, 0};
  double dt = 1e-3;
  std::string dt_hint;                  // the time-step guard's advice (scene key to change)
  bool record = false;                  // keep the time series
  SnapshotSeries* snapshots = nullptr;  // frames for ParaView (the series decides when)
};

struct ImpactResult {
  double mass = 0, reduced_mass = 0;  // moving sphere's mass; m* of the contact
  double duration = 0;                // measured contact duration (overlap zero crossings)
  double max_overlap = 0, max_normal_force = 0;
  double vn_in = 0, vn_out = 0;       // relative normal velocity of the centres (approach > 0 in)
  double vt_in = 0, vt_out = 0;       // relative tangential (x) velocity of the centres
  double vc_in = 0, vc_out = 0;       // relative tangential (x) velocity of the contact points
  double spin_in = 0, spin_out = 0;   // angular velocity about y of the moving sphere
  double restitution_normal = 0;      // -vn_out / vn_in (vn_out measured as separation speed)
  double restitution_tangential = 0;  // -vc_out / vc_in
  double rebound_angle = 0;           // atan(vt_out / vn_out) of the relative motion (radians)
  double impulse_normal = 0, impulse_tangential = 0;  // on the moving sphere (along +z, +x)
  bool separated = false;
  long steps = 0;
  // Per step while recording: time, overlap, force on the moving sphere along the normal and
  // along x, and the slip velocity of the contact points along x (v_c); in the contact's own
  // frame (n from the target to the moving sphere: the pair's normal turns as the spheres
  // pass each other), the normal force f.n, the tangential force's magnitude and its power
  // on the slip, f_t . v_c (negative while friction opposes the slip).
  std::vector<double> t, overlap, force_normal, force_tangential, slip;
  std::vector<double> contact_normal_force, contact_tangential_force, friction_power,
      contact_slip_speed;
};

namespace detail {

// The sphere and its target, their host mirrors and the measurements of impact(), one
// concern a method.
template <class ExecSpace, class Model>
class ImpactRun {
 public:
  ImpactRun(const Model& model, const ImpactSetup& s)
      : s_(s),
        n_(s.wall ? 1 : 2),
        a1_(s.radius1),
        a2_(s.wall ? 0.0 : s.radius2),
        reach_(a1_ + (s.wall ? 0.0 : a2_)),
        sys_(Particles<ExecSpace>::from_host(impact_particles()), impact_box(), model,
             impact_params()) {
    if (s.wall) {
      WallSpec w;
      w.name = "target";
      w.normal[0] = 0, w.normal[1] = 0, w.normal[2] = -1;  // particles above z = 0
      w.material = s.wall_material;
      sys_.set_walls({w});
    }
    {
      auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys_.particles().w);
      for (int d = 0; d < 3; ++d) {
        w(0, d) = s.spin[d];
        if (!s.wall) w(1, d) = s.target_spin[d];
      }
      Kokkos::deep_copy(sys_.particles().w, w);
      sys_.refresh_forces();
    }
    xh_ = Kokkos::create_mirror_view(sys_.particles().x);
    vh_ = Kokkos::create_mirror_view(sys_.particles().v);
    wh_ = Kokkos::create_mirror_view(sys_.particles().w);
    fh_ = Kokkos::create_mirror_view(sys_.particles().f);
    mh_ = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys_.particles().mass);
    r_.mass = mh_(0);
    r_.reduced_mass = s.wall ? mh_(0) : mh_(0) * mh_(1) / (mh_(0) + mh_(1));
  }

  ImpactResult run(const Model& model) {
    Kin k = kin();
    r_.vn_in = k.vn, r_.vt_in = k.vt, r_.vc_in = k.vc, r_.spin_in = k.spin;
    const double v0[3] = {vh_(0, 0), vh_(0, 1), vh_(0, 2)};
    const long max_steps = step_bound(model);
    double prev = k.overlap, t_start = -1, t_end = -1;
    if (s_.snapshots) s_.snapshots->sample(sys_);
    for (long step = 1; step <= max_steps; ++step) {
      sys_.step(1);
      if (s_.snapshots) s_.snapshots->sample(sys_);
      k = kin();
      const double t = step * s_.dt;
      require_finite_state(step, t);
      const double fz = fh_(0, 2);
      if (k.overlap > 0) {
        r_.max_overlap = std::max(r_.max_overlap, k.overlap);
        r_.max_normal_force = std::max(r_.max_normal_force, fz);
      }
      if (s_.record) record(t, k);
      if (t_start < 0 && prev <= 0 && k.overlap > 0)
        t_start = t - s_.dt * k.overlap / (k.overlap - prev);
      if (t_start >= 0 && prev > 0 && k.overlap <= 0) {
        t_end = t - s_.dt * k.overlap / (k.overlap - prev);
        r_.separated = true;
        r_.steps = step;
        break;
      }
      prev = k.overlap;
    }
    if (s_.snapshots) s_.snapshots->finish(sys_);
    if (!r_.separated) refuse_endless(max_steps, t_start < 0);
    r_.duration = r_.separated ? t_end - t_start : 0.0;
    r_.vn_out = -k.vn, r_.vt_out = k.vt, r_.vc_out = k.vc, r_.spin_out = k.spin;
    r_.restitution_normal = r_.vn_in != 0 ? r_.vn_out / r_.vn_in : 0.0;
    r_.restitution_tangential = r_.vc_in != 0 ? -r_.vc_out / r_.vc_in : 0.0;
    r_.rebound_angle = std::atan2(r_.vt_out, r_.vn_out);
    r_.impulse_normal = r_.mass * (vh_(0, 2) - v0[2]);
    r_.impulse_tangential = r_.mass * (vh_(0, 0) - v0[0]);
    return r_;
  }

 private:
  // Relative kinematics along the fixed normal z and tangent x.
  struct Kin {
    double overlap, vn, vt, vc, spin;
  };

  HostParticles impact_particles() const {
    const double c = std::cos(s_.angle), sn = std::sin(s_.angle);
    const double gap = 5.0 * s_.speed * c * s_.dt + 1e-9 * reach_;  // a few steps of approach
    HostParticles h;
    h.resize(n_);
    h.x[0] = 0, h.y[0] = 0, h.z[0] = reach_ + gap;
    const double u[3] = {s_.wall ? 0.0 : s_.target_velocity[0],
                         s_.wall ? 0.0 : s_.target_velocity[1],
                         s_.wall ? 0.0 : s_.target_velocity[2]};
    h.vx[0] = u[0] + s_.speed * sn, h.vy[0] = u[1], h.vz[0] = u[2] - s_.speed * c;
    h.radius[0] = a1_, h.density[0] = s_.density1, h.species[0] = s_.species1;
    if (!s_.wall) {
      h.radius[1] = a2_, h.density[1] = s_.density2, h.species[1] = s_.species2;
      h.vx[1] = u[0], h.vy[1] = u[1], h.vz[1] = u[2];
    }
    return h;
  }
  // A closed box far larger than the contact: no periodic images, cells cover the scene.
  PeriodicBox impact_box() const {
    PeriodicBox box;
    const double edge = 12.0 * std::max(a1_, a2_);
    for (int d = 0; d < 3; ++d) box.lo[d] = -0.5 * edge, box.len[d] = edge, box.periodic[d] = false;
    return box;
  }
  DemParams impact_params() const {
    DemParams params;
    params.dt = s_.dt;
    params.dt_hint = s_.dt_hint;
    params.skin = 0.1 * reach_;
    params.max_overlap = 1.0;
    params.sort = false;  // the harness addresses the spheres as particles 0 and 1
    return params;
  }

  // Generous bound: 200 undamped half periods at the guard stiffness.
  long step_bound(const Model& model) const {
    const double kmax = model.stiffness(reach_, 2 * reach_);
    return static_cast<long>(200.0 * M_PI * std::sqrt(r_.reduced_mass / kmax) / s_.dt) + 100000;
  }

  Kin kin() {
    Kokkos::deep_copy(xh_, sys_.particles().x);
    Kokkos::deep_copy(vh_, sys_.particles().v);
    Kokkos::deep_copy(wh_, sys_.particles().w);
    Kokkos::deep_copy(fh_, sys_.particles().f);
    Kin k;
    const double z2 = s_.wall ? 0.0 : xh_(1, 2);
    k.overlap = reach_ - (xh_(0, 2) - z2);
    const double v2[3] = {s_.wall ? 0.0 : vh_(1, 0), 0.0, s_.wall ? 0.0 : vh_(1, 2)};
    k.vn = -(vh_(0, 2) - v2[2]);  // approach speed
    k.vt = vh_(0, 0) - v2[0];
    // Contact point below sphere 1 at lever a1 (above sphere 2 at a2): v + w x (-a1 z).
    const double l1 = a1_ - 0.5 * std::max(k.overlap, 0.0);
    const double l2 = s_.wall ? 0.0 : a2_ - 0.5 * std::max(k.overlap, 0.0);
    const double w2y = s_.wall ? 0.0 : wh_(1, 1);
    k.vc = (vh_(0, 0) - wh_(0, 1) * l1) - (v2[0] + w2y * l2);
    k.spin = wh_(0, 1);
    return k;
  }

  // A NaN must stop the impact, not end it: a NaN overlap reads as "separated".
  void require_finite_state(long step, double t) const {
    static const char* axis[] = {"x", "y", "z"};
    for (int i = 0; i < n_; ++i)
      for (int d = 0; d < 3; ++d) {
        const std::string who = " of sphere " + std::to_string(i + 1) + " along " + axis[d];
        require_finite(xh_(i, d), "position" + who, step, t);
        require_finite(vh_(i, d), "velocity" + who, step, t);
        require_finite(wh_(i, d), "angular velocity" + who, step, t);
        require_finite(fh_(i, d), "force" + who, step, t);
      }
  }

  // The series of record mode: along the fixed axes, then in the contact's own frame (n from
  // the target to the moving sphere, the levers a - delta/2 as in the kernels).
  void record(double t, const Kin& k) {
    const bool touching = k.overlap > 0;
    r_.t.push_back(t);
    r_.overlap.push_back(k.overlap);
    r_.force_normal.push_back(touching ? fh_(0, 2) : 0.0);
    r_.force_tangential.push_back(touching ? fh_(0, 0) : 0.0);
    r_.slip.push_back(k.vc);
    double n[3], f[3], vc[3];
    double len = 0;
    for (int d = 0; d < 3; ++d) {
      n[d] = s_.wall ? (d == 2 ? 1.0 : 0.0) : xh_(0, d) - xh_(1, d);
      len += n[d] * n[d];
    }
    len = std::sqrt(len);
    double fn = 0;
    for (int d = 0; d < 3; ++d) n[d] /= len, f[d] = fh_(0, d), fn += f[d] * n[d];
    const double ov = std::max(k.overlap, 0.0);
    const double l1 = a1_ - 0.5 * ov, l2 = s_.wall ? 0.0 : a2_ - 0.5 * ov;
    for (int d = 0; d < 3; ++d) {
      const int e1 = (d + 1) % 3, e2 = (d + 2) % 3;
      // v + w x (-l1 n) for sphere 1, v + w x (l2 n) for the target.
      const double c1 = -l1 * (wh_(0, e1) * n[e2] - wh_(0, e2) * n[e1]);
      const double v2 = s_.wall ? 0.0 : vh_(1, d) + l2 * (wh_(1, e1) * n[e2] - wh_(1, e2) * n[e1]);
      vc[d] = vh_(0, d) + c1 - v2;
    }
    const double vcn = vc[0] * n[0] + vc[1] * n[1] + vc[2] * n[2];
    double ft2 = 0, power = 0, slip2 = 0;
    for (int d = 0; d < 3; ++d) {
      const double ft = f[d] - fn * n[d], vt = vc[d] - vcn * n[d];
      ft2 += ft * ft, power += ft * vt, slip2 += vt * vt;
    }
    r_.contact_normal_force.push_back(touching ? fn : 0.0);
    r_.contact_tangential_force.push_back(touching ? std::sqrt(ft2) : 0.0);
    r_.friction_power.push_back(touching ? power : 0.0);
    r_.contact_slip_speed.push_back(std::sqrt(slip2));
  }

  [[noreturn]] void refuse_endless(long max_steps, bool never_touched) const {
    std::ostringstream msg;
    msg << "the impact at speed " << s_.speed << " and incidence " << s_.angle * 180.0 / M_PI
        << " deg did not end within " << max_steps << " steps (200 undamped contact times): "
        << (never_touched ? "the spheres never touched" : "the spheres stayed in contact")
        << "; check the materials' stiffness and restitution";
    throw PhysicsError(msg.str());
  }

  using HostVec =
      decltype(Kokkos::create_mirror_view(std::declval<typename Particles<ExecSpace>::vec_view>()));
  using HostScalar = decltype(Kokkos::create_mirror_view_and_copy(
      Kokkos::HostSpace(), std::declval<typename Particles<ExecSpace>::scalar_view>()));
  const ImpactSetup& s_;
  int n_;
  double a1_, a2_, reach_;
  DemSystem<ExecSpace, Model> sys_;
  HostVec xh_, vh_, wh_, fh_;
  HostScalar mh_;
  ImpactResult r_;
};

}  // namespace detail

template <class ExecSpace, class Model>
ImpactResult impact(const Model& model, const ImpactSetup& s) {
  return detail::ImpactRun<ExecSpace, Model>(model, s).run(model);
}

}  // namespace granular
