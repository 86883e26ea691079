// Head-on collision of two spheres, measured the way an experiment would: contact
// duration from the (interpolated) times the overlap crosses zero, restitution from the
// relative velocities long before and after. Shared by the scene and the tests.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <vector>

#include "kernels/contact_model.hpp"
#include "kernels/dem_system.hpp"

namespace granular {

struct CollisionSetup {
  double radius1 = 1.0, radius2 = 1.0;
  double density = 1.0;
  double speed = 1.0;  // sphere 1 moves at +speed towards sphere 2 at rest
  double dt = 1e-3;
  bool record = false;  // keep the overlap/force/energy series
};

struct CollisionResult {
  double duration = 0;     // measured contact duration
  double restitution = 0;  // measured normal restitution
  double momentum_before = 0, momentum_after = 0;  // x-momentum (y, z stay exactly 0)
  double max_energy_error = 0;  // max |E(t) - E(0)| / E(0) over the run (meaningful if undamped)
  double mass1 = 0, mass2 = 0;
  long steps = 0;
  std::vector<double> t, delta, force, energy;
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
  h.radius = {s.radius1, s.radius2};
  h.density = {s.density, s.density};

  DemParams params;
  params.dt = s.dt;
  params.skin = 0.1 * sum;
  params.max_overlap = 1.0;
  DemSystem<ExecSpace, Model> sys(Particles<ExecSpace>::from_host(h), box, model, params);

  auto xh = Kokkos::create_mirror_view(sys.particles().x);
  auto vh = Kokkos::create_mirror_view(sys.particles().v);
  auto fh = Kokkos::create_mirror_view(sys.particles().f);
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
  double delta, vrel, p, e0;
  sample(delta, vrel, p, e0);
  r.momentum_before = p;
  const double v_in = vrel;
  double t_start = -1, t_end = -1, prev_delta = delta;
  // Generous bound on the collision length: 100 undamped half periods at the guard stiffness.
  const double k = model.stiffness(params.max_overlap * std::min(s.radius1, s.radius2), 2 * sum);
  const long max_steps =
      static_cast<long>(100.0 * M_PI / std::sqrt(k * (1 / r.mass1 + 1 / r.mass2)) / s.dt) + 1000;
  double v_out = 0, e = e0;
  for (long k = 1; k <= max_steps; ++k) {
    sys.step(1);
    sample(delta, vrel, p, e);
    const double t = k * s.dt;
    if (s.record) {
      r.t.push_back(t);
      r.delta.push_back(delta);
      r.force.push_back(fh(1, 0));  // force on the sphere at rest, along the line of centres
      r.energy.push_back(e);
    }
    r.max_energy_error = std::max(r.max_energy_error, std::fabs(e - e0) / e0);
    // Linear interpolation of the zero crossings of the overlap.
    if (t_start < 0 && prev_delta <= 0 && delta > 0) t_start = t - s.dt * delta / (delta - prev_delta);
    if (t_start >= 0 && prev_delta > 0 && delta <= 0) {
      t_end = t - s.dt * delta / (delta - prev_delta);
      v_out = vrel;
      r.steps = k;
      break;
    }
    prev_delta = delta;
  }
  r.duration = t_end - t_start;
  r.restitution = -v_out / v_in;
  r.momentum_after = p;
  return r;
}

}  // namespace granular
