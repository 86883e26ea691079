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

template <class ExecSpace, class Model>
ImpactResult impact(const Model& model, const ImpactSetup& s) {
  const int n = s.wall ? 1 : 2;
  const double a1 = s.radius1, a2 = s.wall ? 0.0 : s.radius2;
  const double reach = a1 + (s.wall ? 0.0 : a2);
  const double c = std::cos(s.angle), sn = std::sin(s.angle);
  const double gap = 5.0 * s.speed * c * s.dt + 1e-9 * reach;  // a few steps of approach
  HostParticles h;
  h.resize(n);
  h.x[0] = 0, h.y[0] = 0, h.z[0] = reach + gap;
  const double u[3] = {s.wall ? 0.0 : s.target_velocity[0], s.wall ? 0.0 : s.target_velocity[1],
                       s.wall ? 0.0 : s.target_velocity[2]};
  h.vx[0] = u[0] + s.speed * sn, h.vy[0] = u[1], h.vz[0] = u[2] - s.speed * c;
  h.radius[0] = a1, h.density[0] = s.density1, h.species[0] = s.species1;
  if (!s.wall) {
    h.radius[1] = a2, h.density[1] = s.density2, h.species[1] = s.species2;
    h.vx[1] = u[0], h.vy[1] = u[1], h.vz[1] = u[2];
  }

  // A closed box far larger than the contact: no periodic images, cells cover the scene.
  PeriodicBox box;
  const double edge = 12.0 * std::max(a1, a2);
  for (int d = 0; d < 3; ++d) box.lo[d] = -0.5 * edge, box.len[d] = edge, box.periodic[d] = false;
  DemParams params;
  params.dt = s.dt;
  params.dt_hint = s.dt_hint;
  params.skin = 0.1 * reach;
  params.max_overlap = 1.0;
  params.sort = false;  // the harness addresses the spheres as particles 0 and 1
  DemSystem<ExecSpace, Model> sys(Particles<ExecSpace>::from_host(h), box, model, params);
  if (s.wall) {
    WallSpec w;
    w.name = "target";
    w.normal[0] = 0, w.normal[1] = 0, w.normal[2] = -1;  // particles above z = 0
    w.material = s.wall_material;
    sys.set_walls({w});
  }
  {
    auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().w);
    for (int d = 0; d < 3; ++d) {
      w(0, d) = s.spin[d];
      if (!s.wall) w(1, d) = s.target_spin[d];
    }
    Kokkos::deep_copy(sys.particles().w, w);
    sys.refresh_forces();
  }
  auto xh = Kokkos::create_mirror_view(sys.particles().x);
  auto vh = Kokkos::create_mirror_view(sys.particles().v);
  auto wh = Kokkos::create_mirror_view(sys.particles().w);
  auto fh = Kokkos::create_mirror_view(sys.particles().f);
  auto mh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().mass);

  ImpactResult r;
  r.mass = mh(0);
  r.reduced_mass = s.wall ? mh(0) : mh(0) * mh(1) / (mh(0) + mh(1));
  // Relative kinematics along the fixed normal z and tangent x.
  struct Kin {
    double overlap, vn, vt, vc, spin;
  };
  auto kin = [&]() {
    Kokkos::deep_copy(xh, sys.particles().x);
    Kokkos::deep_copy(vh, sys.particles().v);
    Kokkos::deep_copy(wh, sys.particles().w);
    Kokkos::deep_copy(fh, sys.particles().f);
    Kin k;
    const double z2 = s.wall ? 0.0 : xh(1, 2);
    k.overlap = reach - (xh(0, 2) - z2);
    const double v2[3] = {s.wall ? 0.0 : vh(1, 0), 0.0, s.wall ? 0.0 : vh(1, 2)};
    k.vn = -(vh(0, 2) - v2[2]);  // approach speed
    k.vt = vh(0, 0) - v2[0];
    // Contact point below sphere 1 at lever a1 (above sphere 2 at a2): v + w x (-a1 z).
    const double l1 = a1 - 0.5 * std::max(k.overlap, 0.0);
    const double l2 = s.wall ? 0.0 : a2 - 0.5 * std::max(k.overlap, 0.0);
    const double w2y = s.wall ? 0.0 : wh(1, 1);
    k.vc = (vh(0, 0) - wh(0, 1) * l1) - (v2[0] + w2y * l2);
    k.spin = wh(0, 1);
    return k;
  };
  Kin k = kin();
  r.vn_in = k.vn, r.vt_in = k.vt, r.vc_in = k.vc, r.spin_in = k.spin;
  const double v0[3] = {vh(0, 0), vh(0, 1), vh(0, 2)};
  // Generous bound: 200 undamped half periods at the guard stiffness.
  const double kmax = model.stiffness(reach, 2 * reach);
  const long max_steps =
      static_cast<long>(200.0 * M_PI * std::sqrt(r.reduced_mass / kmax) / s.dt) + 100000;
  double prev = k.overlap, t_start = -1, t_end = -1;
  if (s.snapshots) s.snapshots->sample(sys);
  for (long step = 1; step <= max_steps; ++step) {
    sys.step(1);
    if (s.snapshots) s.snapshots->sample(sys);
    k = kin();
    const double t = step * s.dt;
    // A NaN must stop the impact, not end it: a NaN overlap reads as "separated".
    for (int i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) {
        static const char* axis[] = {"x", "y", "z"};
        const std::string who = " of sphere " + std::to_string(i + 1) + " along " + axis[d];
        require_finite(xh(i, d), "position" + who, step, t);
        require_finite(vh(i, d), "velocity" + who, step, t);
        require_finite(wh(i, d), "angular velocity" + who, step, t);
        require_finite(fh(i, d), "force" + who, step, t);
      }
    const double fz = fh(0, 2), fx = fh(0, 0);
    if (k.overlap > 0) {
      r.max_overlap = std::max(r.max_overlap, k.overlap);
      r.max_normal_force = std::max(r.max_normal_force, fz);
    }
    if (s.record) {
      r.t.push_back(t);
      r.overlap.push_back(k.overlap);
      r.force_normal.push_back(k.overlap > 0 ? fz : 0.0);
      r.force_tangential.push_back(k.overlap > 0 ? fx : 0.0);
      r.slip.push_back(k.vc);
      // The contact frame: n, the levers a - delta/2 as in the kernels.
      double n[3], f[3], vc[3];
      double len = 0;
      for (int d = 0; d < 3; ++d) {
        n[d] = s.wall ? (d == 2 ? 1.0 : 0.0) : xh(0, d) - xh(1, d);
        len += n[d] * n[d];
      }
      len = std::sqrt(len);
      double fn = 0;
      for (int d = 0; d < 3; ++d) n[d] /= len, f[d] = fh(0, d), fn += f[d] * n[d];
      const double ov = std::max(k.overlap, 0.0);
      const double l1 = a1 - 0.5 * ov, l2 = s.wall ? 0.0 : a2 - 0.5 * ov;
      for (int d = 0; d < 3; ++d) {
        const int e1 = (d + 1) % 3, e2 = (d + 2) % 3;
        // v + w x (-l1 n) for sphere 1, v + w x (l2 n) for the target.
        const double c1 = -l1 * (wh(0, e1) * n[e2] - wh(0, e2) * n[e1]);
        const double v2 = s.wall ? 0.0 : vh(1, d) + l2 * (wh(1, e1) * n[e2] - wh(1, e2) * n[e1]);
        vc[d] = vh(0, d) + c1 - v2;
      }
      const double vcn = vc[0] * n[0] + vc[1] * n[1] + vc[2] * n[2];
      double ft2 = 0, power = 0, slip2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double ft = f[d] - fn * n[d], vt = vc[d] - vcn * n[d];
        ft2 += ft * ft, power += ft * vt, slip2 += vt * vt;
      }
      r.contact_normal_force.push_back(k.overlap > 0 ? fn : 0.0);
      r.contact_tangential_force.push_back(k.overlap > 0 ? std::sqrt(ft2) : 0.0);
      r.friction_power.push_back(k.overlap > 0 ? power : 0.0);
      r.contact_slip_speed.push_back(std::sqrt(slip2));
    }
    if (t_start < 0 && prev <= 0 && k.overlap > 0)
      t_start = t - s.dt * k.overlap / (k.overlap - prev);
    if (t_start >= 0 && prev > 0 && k.overlap <= 0) {
      t_end = t - s.dt * k.overlap / (k.overlap - prev);
      r.separated = true;
      r.steps = step;
      break;
    }
    prev = k.overlap;
  }
  if (s.snapshots) s.snapshots->finish(sys);
  if (!r.separated) {
    std::ostringstream msg;
    msg << "the impact at speed " << s.speed << " and incidence " << s.angle * 180.0 / M_PI
        << " deg did not end within " << max_steps << " steps (200 undamped contact times): "
        << (t_start < 0 ? "the spheres never touched" : "the spheres stayed in contact")
        << "; check the materials' stiffness and restitution";
    throw PhysicsError(msg.str());
  }
  r.duration = r.separated ? t_end - t_start : 0.0;
  r.vn_out = -k.vn, r.vt_out = k.vt, r.vc_out = k.vc, r.spin_out = k.spin;
  r.restitution_normal = r.vn_in != 0 ? r.vn_out / r.vn_in : 0.0;
  r.restitution_tangential = r.vc_in != 0 ? -r.vc_out / r.vc_in : 0.0;
  r.rebound_angle = std::atan2(r.vt_out, r.vn_out);
  r.impulse_normal = r.mass * (vh(0, 2) - v0[2]);
  r.impulse_tangential = r.mass * (vh(0, 0) - v0[0]);
  return r;
}

}  // namespace granular
