// Head-on collision of two spheres, measured the way an experiment would: contact
// duration from the (interpolated) times the overlap crosses zero, restitution from the
// relative velocities long before and after. Shared by the scene and the tests.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
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

namespace detail {

// The pair, its host mirrors and the measurements of collide_head_on, one concern a method.
template <class ExecSpace, class Model>
class HeadOnCollision {
 public:
  HeadOnCollision(const Model& model, const CollisionSetup& s)
      : s_(s),
        sum_(s.radius1 + s.radius2),
        params_(pair_params(s)),
        sys_(Particles<ExecSpace>::from_host(pair_particles(s)), pair_box(s), model, params_) {
    if (s.spin != 0.0) {
      auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys_.particles().w);
      w(0, 2) = s.spin;
      Kokkos::deep_copy(sys_.particles().w, w);
      sys_.refresh_forces();
    }
    xh_ = Kokkos::create_mirror_view(sys_.particles().x);
    vh_ = Kokkos::create_mirror_view(sys_.particles().v);
    fh_ = Kokkos::create_mirror_view(sys_.particles().f);
    wh_ = Kokkos::create_mirror_view(sys_.particles().w);
    ih_ = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys_.particles().inertia);
    mh_ = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys_.particles().mass);
    r_.mass1 = mh_(0), r_.mass2 = mh_(1);
  }

  CollisionResult run(const Model& model) {
    kinematics(r_.slip_before, r_.vy_rel_before, r_.angular_momentum_before);
    r_.ekin_before = ekin();
    Sample a = sample();
    r_.momentum_before = a.p;
    if (!std::isfinite(a.e) || !std::isfinite(a.delta))
      throw PhysicsError(
          "collision: the kinetic energy before contact is not finite: lower the "
          "impact speed");
    const double v_in = a.vrel, e0 = a.e;
    double t_start = -1, t_end = -1, prev_delta = a.delta, v_out = 0;
    const long max_steps = step_bound(model);
    for (long k = 1; k <= max_steps; ++k) {
      if (s_.record) keep_velocities();
      sys_.step(1);
      a = sample();
      if (!std::isfinite(a.delta) || !std::isfinite(a.e))
        throw PhysicsError("collision: the state became non-finite at step " + std::to_string(k) +
                           ": lower the impact speed or raise the steps per contact");
      if (s_.record) {
        average_velocities();
        dissipation(s_.gamma_n);
      }
      const double t = k * s_.dt;
      if (s_.record) record(t, a);
      r_.max_energy_error = std::max(r_.max_energy_error, std::fabs(a.e - e0) / e0);
      // Linear interpolation of the zero crossings of the overlap.
      if (t_start < 0 && prev_delta <= 0 && a.delta > 0)
        t_start = t - s_.dt * a.delta / (a.delta - prev_delta);
      if (t_start >= 0 && prev_delta > 0 && a.delta <= 0) {
        t_end = t - s_.dt * a.delta / (a.delta - prev_delta);
        v_out = a.vrel;
        r_.steps = k;
        break;
      }
      prev_delta = a.delta;
    }
    kinematics(r_.slip_after, r_.vy_rel_after, r_.angular_momentum_after);
    r_.ekin_after = ekin();
    r_.duration = t_end - t_start;
    r_.restitution = -v_out / v_in;
    r_.momentum_after = a.p;
    return r_;
  }

 private:
  struct Sample {
    double delta, vrel, p, e;  // overlap, approach speed, x-momentum, total energy
  };

  static HostParticles pair_particles(const CollisionSetup& s) {
    HostParticles h;
    h.resize(2);
    const double sum = s.radius1 + s.radius2, edge = box_edge(s);
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
    return h;
  }
  // Far larger than the neighbour cutoff: no image contacts.
  static double box_edge(const CollisionSetup& s) { return 8.0 * (s.radius1 + s.radius2); }
  static PeriodicBox pair_box(const CollisionSetup& s) {
    PeriodicBox box;
    for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = box_edge(s);
    return box;
  }
  static DemParams pair_params(const CollisionSetup& s) {
    DemParams params;
    params.dt = s.dt;
    params.skin = 0.1 * (s.radius1 + s.radius2);
    params.max_overlap = 1.0;
    params.sort = false;  // the harness addresses the spheres as particles 0 and 1
    return params;
  }

  // Generous bound on the collision length: 100 undamped half periods at the guard stiffness.
  long step_bound(const Model& model) const {
    const double k =
        model.stiffness(params_.max_overlap * std::min(s_.radius1, s_.radius2), 2 * sum_);
    const double longest = 100.0 * M_PI / std::sqrt(k * (1 / r_.mass1 + 1 / r_.mass2)) / s_.dt;
    if (!(longest < 1e9))  // also a stiffness so small that its period overflows
      throw PhysicsError("collision: the contact would last more than 1e9 steps (stiffness " +
                         std::to_string(k) + "): raise the contact stiffness or the time step");
    return static_cast<long>(longest) + 1000;
  }

  Sample sample() {
    Kokkos::deep_copy(xh_, sys_.particles().x);
    Kokkos::deep_copy(vh_, sys_.particles().v);
    Kokkos::deep_copy(fh_, sys_.particles().f);
    Sample a;
    const double dx = sys_.box().min_image(xh_(1, 0) - xh_(0, 0), 0);
    a.delta = sum_ - std::fabs(dx);
    a.vrel = vh_(0, 0) - vh_(1, 0);  // approach speed, positive while closing
    a.p = mh_(0) * vh_(0, 0) + mh_(1) * vh_(1, 0);
    const Measurements m = sys_.measure();
    a.e = m.ekin + m.epot;
    return a;
  }

  // Slip of the contact points (lever arms at mid-overlap, as in the force kernel) and the
  // angular momentum about the centre of mass.
  void kinematics(double& slip, double& vy_rel, double L[3]) {
    Kokkos::deep_copy(xh_, sys_.particles().x);
    Kokkos::deep_copy(vh_, sys_.particles().v);
    Kokkos::deep_copy(wh_, sys_.particles().w);
    const double dx = sys_.box().min_image(xh_(1, 0) - xh_(0, 0), 0);
    const double delta = std::max(0.0, sum_ - std::fabs(dx));
    const double l0 = s_.radius1 - 0.5 * delta, l1 = s_.radius2 - 0.5 * delta;
    // Contact point velocities along y for the normal along x: v_y + w_z * (offset along x).
    slip = (vh_(0, 1) + wh_(0, 2) * l0) - (vh_(1, 1) - wh_(1, 2) * l1);
    vy_rel = vh_(0, 1) - vh_(1, 1);
    const double M = mh_(0) + mh_(1);
    double X[3];
    for (int d = 0; d < 3; ++d) X[d] = (mh_(0) * xh_(0, d) + mh_(1) * xh_(1, d)) / M, L[d] = 0;
    for (int i = 0; i < 2; ++i) {
      const double r[3] = {xh_(i, 0) - X[0], xh_(i, 1) - X[1], xh_(i, 2) - X[2]};
      const double p[3] = {mh_(i) * vh_(i, 0), mh_(i) * vh_(i, 1), mh_(i) * vh_(i, 2)};
      double c[3];
      cross3(r, p, c);
      for (int d = 0; d < 3; ++d) L[d] += c[d] + ih_(i) * wh_(i, d);
    }
  }

  double ekin() const {
    double e = 0;
    for (int i = 0; i < 2; ++i)
      for (int d = 0; d < 3; ++d)
        e += 0.5 * mh_(i) * vh_(i, d) * vh_(i, d) + 0.5 * ih_(i) * wh_(i, d) * wh_(i, d);
    return e;
  }

  // Velocities before the step, for the mid-step average of average_velocities.
  void keep_velocities() {
    Kokkos::deep_copy(vh_, sys_.particles().v);
    Kokkos::deep_copy(wh_, sys_.particles().w);
    for (int i = 0; i < 2; ++i)
      for (int d = 0; d < 3; ++d) v_mid_[i][d] = vh_(i, d), w_mid_[i][d] = wh_(i, d);
  }
  void average_velocities() {
    Kokkos::deep_copy(wh_, sys_.particles().w);
    for (int i = 0; i < 2; ++i)
      for (int d = 0; d < 3; ++d)
        v_mid_[i][d] = 0.5 * (v_mid_[i][d] + vh_(i, d)),
        w_mid_[i][d] = 0.5 * (w_mid_[i][d] + wh_(i, d));
  }

  // Dissipation of the contact over the last step, from the force on sphere 2 and the
  // relative velocity of its contact point at mid-step (the force was evaluated with the
  // mid-step velocity; the difference is of the integrator's order).
  void dissipation(double gamma_n) {
    double n[3] = {xh_(1, 0) - xh_(0, 0), xh_(1, 1) - xh_(0, 1), xh_(1, 2) - xh_(0, 2)};
    const double len = std::sqrt(dot3(n, n));
    for (double& c : n) c /= len;
    const double delta = sum_ - len;
    if (delta <= 0) return;
    const double l0 = s_.radius1 - 0.5 * delta, l1 = s_.radius2 - 0.5 * delta;
    // Contact point of 2 relative to that of 1: v2 - l2 w2 x n - (v1 + l1 w1 x n).
    double aw[3], c[3], vrel[3];
    for (int d = 0; d < 3; ++d) aw[d] = l1 * w_mid_[1][d] + l0 * w_mid_[0][d];
    cross3(aw, n, c);
    for (int d = 0; d < 3; ++d) vrel[d] = v_mid_[1][d] - v_mid_[0][d] - c[d];
    const double vn = dot3(vrel, n);
    const double f[3] = {fh_(1, 0), fh_(1, 1), fh_(1, 2)};
    const double fn = dot3(f, n);
    double ft_dot_vt = 0;
    for (int d = 0; d < 3; ++d) ft_dot_vt += (f[d] - fn * n[d]) * (vrel[d] - vn * n[d]);
    r_.dissipated_normal += gamma_n * vn * vn * s_.dt;
    r_.dissipated_tangential += -ft_dot_vt * s_.dt;
  }

  // The series of record mode: the force on the sphere at rest, along the line of centres and
  // split along the actual normal.
  void record(double t, const Sample& a) {
    r_.t.push_back(t);
    r_.delta.push_back(a.delta);
    r_.force.push_back(fh_(1, 0));
    const double nx = xh_(1, 0) - xh_(0, 0), ny = xh_(1, 1) - xh_(0, 1), nz = xh_(1, 2) - xh_(0, 2);
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    const double fn = (fh_(1, 0) * nx + fh_(1, 1) * ny + fh_(1, 2) * nz) / len;
    const double ftx = fh_(1, 0) - fn * nx / len, fty = fh_(1, 1) - fn * ny / len,
                 ftz = fh_(1, 2) - fn * nz / len;
    r_.force_normal.push_back(a.delta > 0 ? fn : 0.0);
    r_.force_tangential.push_back(a.delta > 0 ? std::sqrt(ftx * ftx + fty * fty + ftz * ftz) : 0.0);
    r_.energy.push_back(a.e);
  }

  using Sys = DemSystem<ExecSpace, Model>;
  const CollisionSetup& s_;
  double sum_;
  DemParams params_;
  Sys sys_;
  using HostVec =
      decltype(Kokkos::create_mirror_view(std::declval<typename Particles<ExecSpace>::vec_view>()));
  using HostScalar = decltype(Kokkos::create_mirror_view_and_copy(
      Kokkos::HostSpace(), std::declval<typename Particles<ExecSpace>::scalar_view>()));
  HostVec xh_, vh_, fh_, wh_;
  HostScalar ih_, mh_;
  double v_mid_[2][3] = {}, w_mid_[2][3] = {};
  CollisionResult r_;
};

}  // namespace detail

template <class ExecSpace, class Model>
CollisionResult collide_head_on(const Model& model, const CollisionSetup& s) {
  return detail::HeadOnCollision<ExecSpace, Model>(model, s).run(model);
}

}  // namespace granular
