// Head-on collision of two spheres, measured the way an experiment would: contact
// duration from the (interpolated) times the overlap crosses zero, restitution from the
// relative velocities long before and after. Shared by the scene and the tests.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "core/run/error.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"

namespace granular {

struct CollisionSetup {
  double radius1 = 1.0, radius2 = 1.0;
  double density = 1.0;
  double speed = 1.0;             // sphere 1 moves at +speed towards sphere 2 at rest
  double tangential_speed = 0.0;  // and at this speed along y (oblique impact)
  double spin = 0.0;              // angular velocity of sphere 1 about z
  int species1 = 0, species2 = 0;
  double gamma_n = 0.0;  // normal viscosity of the model, for the dissipation bookkeeping
  double dt = 1e-3;
  bool record = false;  // keep the overlap/force/energy series
};

struct CollisionResult {
  double duration = 0;                             // measured contact duration
  double restitution = 0;                          // measured normal restitution
  double momentum_before = 0, momentum_after = 0;  // x-momentum (y, z stay exactly 0)
  double max_energy_error = 0;  // max |E(t) - E(0)| / E(0) over the run (meaningful if undamped)
  double slip_before = 0, slip_after = 0;      // y-velocity of 1's contact point relative to 2's
  double vy_rel_before = 0, vy_rel_after = 0;  // relative y-velocity of the centres
  double angular_momentum_before[3] = {},
         angular_momentum_after[3] = {};  // about the centre of mass
  double mass1 = 0, mass2 = 0;
  long steps = 0;
  std::vector<double> t, delta, force, energy;
  std::vector<double> force_normal, force_tangential;  // on sphere 2, split along the actual normal
  // Energy bookkeeping (record mode): kinetic energy (translational + rotational) at the
  // start and end, and the dissipation sums over the steps: normal dashpot gamma_n ddelta^2 dt
  // and tangential -f_t . v_t dt (sliding friction plus tangential dashpot).
  double ekin_before = 0, ekin_after = 0;
  double dissipated_normal = 0, dissipated_tangential = 0;
};

template <class ExecSpace, class Model>
CollisionResult collide_head_on(const Model& model, const CollisionSetup& s) {
  HostParticles h;
  h.resize(2);
  const double sum = s.radius1 + s.radius2;
  PeriodicBox box;
  const double edge = 8.0 * sum;  // far larger than the neighbour cutoff: no image contacts
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = edge;
  // Start a few steps before touching so the approach is sampled.
  const double gap = 5.0 * s.speed * s.dt;
  h.x = {0.5 * edge - 0.5 * sum - gap, 0.5 * edge + 0.5 * sum};
  h.y = {0.5 * edge, 0.5 * edge};
  h.z = {0.5 * edge, 0.5 * edge};
  h.vx = {s.speed, 0.0};
  h.vy = {s.tangential_speed, 0.0};
  h.radius = {s.radius1, s.radius2};
  h.density = {s.density, s.density};
  h.species = {s.species1, s.species2};

  DemParams params;
  params.dt = s.dt;
  params.skin = 0.1 * sum;
  params.max_overlap = 1.0;
  params.sort = false;  // the harness addresses the spheres as particles 0 and 1
  DemSystem<ExecSpace, Model> sys(Particles<ExecSpace>::from_host(h), box, model, params);
  if (s.spin != 0.0) {
    auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().w);
    w(0, 2) = s.spin;
    Kokkos::deep_copy(sys.particles().w, w);
    sys.refresh_forces();
  }

  auto xh = Kokkos::create_mirror_view(sys.particles().x);
  auto vh = Kokkos::create_mirror_view(sys.particles().v);
  auto fh = Kokkos::create_mirror_view(sys.particles().f);
  auto wh = Kokkos::create_mirror_view(sys.particles().w);
  auto ih = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().inertia);
  auto mh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().mass);
  CollisionResult r;
  r.mass1 = mh(0), r.mass2 = mh(1);
  auto sample = [&](double& delta, double& vrel, double& p, double& e) {
    Kokkos::deep_copy(xh, sys.particles().x);
    Kokkos::deep_copy(vh, sys.particles().v);
    Kokkos::deep_copy(fh, sys.particles().f);
    const double dx = sys.box().min_image(xh(1, 0) - xh(0, 0), 0);
    delta = sum - std::fabs(dx);
    vrel = vh(0, 0) - vh(1, 0);  // approach speed, positive while closing
    p = mh(0) * vh(0, 0) + mh(1) * vh(1, 0);
    const Measurements m = sys.measure();
    e = m.ekin + m.epot;
  };
  // Slip of the contact points (lever arms at mid-overlap, as in the force kernel) and the
  // angular momentum about the centre of mass.
  auto kinematics = [&](double& slip, double& vy_rel, double L[3]) {
    Kokkos::deep_copy(xh, sys.particles().x);
    Kokkos::deep_copy(vh, sys.particles().v);
    Kokkos::deep_copy(wh, sys.particles().w);
    const double dx = sys.box().min_image(xh(1, 0) - xh(0, 0), 0);
    const double delta = std::max(0.0, sum - std::fabs(dx));
    const double l0 = s.radius1 - 0.5 * delta, l1 = s.radius2 - 0.5 * delta;
    // Contact point velocities along y for the normal along x: v_y + w_z * (offset along x).
    slip = (vh(0, 1) + wh(0, 2) * l0) - (vh(1, 1) - wh(1, 2) * l1);
    vy_rel = vh(0, 1) - vh(1, 1);
    const double M = mh(0) + mh(1);
    double X[3];
    for (int d = 0; d < 3; ++d) X[d] = (mh(0) * xh(0, d) + mh(1) * xh(1, d)) / M, L[d] = 0;
    for (int i = 0; i < 2; ++i) {
      const double r[3] = {xh(i, 0) - X[0], xh(i, 1) - X[1], xh(i, 2) - X[2]};
      const double p[3] = {mh(i) * vh(i, 0), mh(i) * vh(i, 1), mh(i) * vh(i, 2)};
      double c[3];
      cross3(r, p, c);
      for (int d = 0; d < 3; ++d) L[d] += c[d] + ih(i) * wh(i, d);
    }
  };
  // Dissipation of the contact over the last step, from the force on sphere 2 and the
  // relative velocity of its contact point, both at the end of the step (the force was
  // evaluated with the mid-step velocity; the difference is of the integrator's order).
  auto ekin = [&]() {
    double e = 0;
    for (int i = 0; i < 2; ++i)
      for (int d = 0; d < 3; ++d)
        e += 0.5 * mh(i) * vh(i, d) * vh(i, d) + 0.5 * ih(i) * wh(i, d) * wh(i, d);
    return e;
  };
  double v_mid[2][3] = {}, w_mid[2][3] = {};
  auto dissipation = [&](double gamma_n) {
    double n[3] = {xh(1, 0) - xh(0, 0), xh(1, 1) - xh(0, 1), xh(1, 2) - xh(0, 2)};
    const double len = std::sqrt(dot3(n, n));
    for (double& c : n) c /= len;
    const double delta = sum - len;
    if (delta <= 0) return;
    const double l0 = s.radius1 - 0.5 * delta, l1 = s.radius2 - 0.5 * delta;
    // Contact point of 2 relative to that of 1: v2 - l2 w2 x n - (v1 + l1 w1 x n).
    double aw[3], c[3], vrel[3];
    for (int d = 0; d < 3; ++d) aw[d] = l1 * w_mid[1][d] + l0 * w_mid[0][d];
    cross3(aw, n, c);
    for (int d = 0; d < 3; ++d) vrel[d] = v_mid[1][d] - v_mid[0][d] - c[d];
    const double vn = dot3(vrel, n);
    const double f[3] = {fh(1, 0), fh(1, 1), fh(1, 2)};
    const double fn = dot3(f, n);
    double ft_dot_vt = 0;
    for (int d = 0; d < 3; ++d) ft_dot_vt += (f[d] - fn * n[d]) * (vrel[d] - vn * n[d]);
    r.dissipated_normal += gamma_n * vn * vn * s.dt;
    r.dissipated_tangential += -ft_dot_vt * s.dt;
  };
  double delta, vrel, p, e0;
  kinematics(r.slip_before, r.vy_rel_before, r.angular_momentum_before);
  r.ekin_before = ekin();
  sample(delta, vrel, p, e0);
  r.momentum_before = p;
  if (!std::isfinite(e0) || !std::isfinite(delta))
    throw PhysicsError(
        "collision: the kinetic energy before contact is not finite: lower the "
        "impact speed");
  const double v_in = vrel;
  double t_start = -1, t_end = -1, prev_delta = delta;
  // Generous bound on the collision length: 100 undamped half periods at the guard stiffness.
  const double k = model.stiffness(params.max_overlap * std::min(s.radius1, s.radius2), 2 * sum);
  const double longest = 100.0 * M_PI / std::sqrt(k * (1 / r.mass1 + 1 / r.mass2)) / s.dt;
  if (!(longest < 1e9))  // also a stiffness so small that its period overflows
    throw PhysicsError("collision: the contact would last more than 1e9 steps (stiffness " +
                       std::to_string(k) + "): raise the contact stiffness or the time step");
  const long max_steps = static_cast<long>(longest) + 1000;
  double v_out = 0, e = e0;
  for (long k = 1; k <= max_steps; ++k) {
    if (s.record) {  // velocities before the step, for the mid-step average below
      Kokkos::deep_copy(vh, sys.particles().v);
      Kokkos::deep_copy(wh, sys.particles().w);
      for (int i = 0; i < 2; ++i)
        for (int d = 0; d < 3; ++d) v_mid[i][d] = vh(i, d), w_mid[i][d] = wh(i, d);
    }
    sys.step(1);
    sample(delta, vrel, p, e);
    if (!std::isfinite(delta) || !std::isfinite(e))
      throw PhysicsError("collision: the state became non-finite at step " + std::to_string(k) +
                         ": lower the impact speed or raise the steps per contact");
    if (s.record) {
      Kokkos::deep_copy(wh, sys.particles().w);
      for (int i = 0; i < 2; ++i)
        for (int d = 0; d < 3; ++d)
          v_mid[i][d] = 0.5 * (v_mid[i][d] + vh(i, d)),
          w_mid[i][d] = 0.5 * (w_mid[i][d] + wh(i, d));
      dissipation(s.gamma_n);
    }
    const double t = k * s.dt;
    if (s.record) {
      r.t.push_back(t);
      r.delta.push_back(delta);
      r.force.push_back(fh(1, 0));  // force on the sphere at rest, along the line of centres
      const double nx = xh(1, 0) - xh(0, 0), ny = xh(1, 1) - xh(0, 1), nz = xh(1, 2) - xh(0, 2);
      const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
      const double fn = (fh(1, 0) * nx + fh(1, 1) * ny + fh(1, 2) * nz) / len;
      const double ftx = fh(1, 0) - fn * nx / len, fty = fh(1, 1) - fn * ny / len,
                   ftz = fh(1, 2) - fn * nz / len;
      r.force_normal.push_back(delta > 0 ? fn : 0.0);
      r.force_tangential.push_back(delta > 0 ? std::sqrt(ftx * ftx + fty * fty + ftz * ftz) : 0.0);
      r.energy.push_back(e);
    }
    r.max_energy_error = std::max(r.max_energy_error, std::fabs(e - e0) / e0);
    // Linear interpolation of the zero crossings of the overlap.
    if (t_start < 0 && prev_delta <= 0 && delta > 0)
      t_start = t - s.dt * delta / (delta - prev_delta);
    if (t_start >= 0 && prev_delta > 0 && delta <= 0) {
      t_end = t - s.dt * delta / (delta - prev_delta);
      v_out = vrel;
      r.steps = k;
      break;
    }
    prev_delta = delta;
  }
  kinematics(r.slip_after, r.vy_rel_after, r.angular_momentum_after);
  r.ekin_after = ekin();
  r.duration = t_end - t_start;
  r.restitution = -v_out / v_in;
  r.momentum_after = p;
  return r;
}

}  // namespace granular
