// Contact and background-damping forces: one generic loop over the neighbour list,
// templated on the contact model (the model struct holds the physics of one pair).
// Each particle sums its own forces in list order (full list: no atomics, reproducible),
// and advances its own copy of each contact's history; the two copies of a contact stay
// exact mirror images because every formula is antisymmetric in (i, j) to the last bit.
#pragma once
#include <Kokkos_Core.hpp>

#include "core/box.hpp"
#include "core/particles.hpp"
#include "kernels/contact_model.hpp"
#include "kernels/neighbor_list.hpp"

namespace granular {

struct Damping {
  double translational = 0.0;  // gamma_b: f = -gamma_b (v - v_affine)
  double rotational = 0.0;     // gamma_br: q = -gamma_br omega
};

// Geometry and relative motion of pair (i, j); false when they do not touch.
// Velocities are stored relative to the affine flow of the deforming box, so the pair's
// affine relative velocity rate * r_ij is added here.
template <class Views>
KOKKOS_INLINE_FUNCTION bool pair_state(const Views& v, const PeriodicBox& b, const double rate[3],
                                       bool rotations, int i, int j, PairState& s) {
  const double rx = b.min_image(v.x(i, 0) - v.x(j, 0), 0);
  const double ry = b.min_image(v.x(i, 1) - v.x(j, 1), 1);
  const double rz = b.min_image(v.x(i, 2) - v.x(j, 2), 2);
  s.ai = v.radius(i), s.aj = v.radius(j);
  const double sum = s.ai + s.aj;
  const double r2 = rx * rx + ry * ry + rz * rz;
  if (r2 >= sum * sum) return false;  // reject before the sqrt
  const double r = Kokkos::Experimental::sqrt(r2);
  const double inv = 1.0 / r;
  s.n[0] = rx * inv, s.n[1] = ry * inv, s.n[2] = rz * inv;
  s.delta = sum - r;
  s.si = v.species(i), s.sj = v.species(j);
  double dv[3] = {v.v(i, 0) - v.v(j, 0) + rate[0] * rx, v.v(i, 1) - v.v(j, 1) + rate[1] * ry,
                  v.v(i, 2) - v.v(j, 2) + rate[2] * rz};
  const double vn = dot3(dv, s.n);
  s.delta_dot = -vn;
  if (rotations) {
    // Contact point in the middle of the overlap, at lever arms a - delta/2 from both
    // centres: then the torques of a tangential force balance exactly and angular
    // momentum is conserved. Contact-point velocity v_i - l_i w_i x n minus v_j + l_j w_j x n.
    const double li = s.ai - 0.5 * s.delta, lj = s.aj - 0.5 * s.delta;
    const double aw[3] = {li * v.w(i, 0) + lj * v.w(j, 0), li * v.w(i, 1) + lj * v.w(j, 1),
                          li * v.w(i, 2) + lj * v.w(j, 2)};
    double c[3];
    cross3(aw, s.n, c);
    for (int d = 0; d < 3; ++d) {
      s.vt[d] = dv[d] - vn * s.n[d] - c[d];
      s.wrel[d] = v.w(i, d) - v.w(j, d);
    }
  } else {
    for (int d = 0; d < 3; ++d) s.vt[d] = dv[d] - vn * s.n[d], s.wrel[d] = 0.0;
  }
  return true;
}

template <class ExecSpace>
struct ParticleViews {
  using mem = typename ExecSpace::memory_space;
  Kokkos::View<double* [3], mem> x, v, w;
  Kokkos::View<double*, mem> radius;
  Kokkos::View<int*, mem> species;
  explicit ParticleViews(const Particles<ExecSpace>& p)
      : x(p.x), v(p.v), w(p.w), radius(p.radius), species(p.species) {}
};

template <class ExecSpace, class Model, class HistoryView>
void compute_forces(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                    const HistoryView& history, const PeriodicBox& box, const Model& model,
                    const Damping& damping, const double strain_rate[3], double dt) {
  const ParticleViews<ExecSpace> pv(p);
  auto f = p.f, torque = p.torque;
  auto offsets = nl.offsets(), neighbors = nl.neighbors();
  const PeriodicBox b = box;
  const Model m = model;
  const double gb = damping.translational, gr = damping.rotational;
  const double rate[3] = {strain_rate[0], strain_rate[1], strain_rate[2]};
  constexpr int H = Model::history;
  constexpr bool rot = Model::rotations;
  Kokkos::parallel_for(
      "dem::compute_forces", Kokkos::RangePolicy<ExecSpace>(0, p.n), KOKKOS_LAMBDA(const int i) {
        double fi[3] = {-gb * pv.v(i, 0), -gb * pv.v(i, 1), -gb * pv.v(i, 2)};
        double qi[3] = {0, 0, 0};
        if (rot)
          for (int d = 0; d < 3; ++d) qi[d] = -gr * pv.w(i, d);
        const double r3[3] = {rate[0], rate[1], rate[2]};
        for (int k = offsets(i); k < offsets(i + 1); ++k) {
          PairState s;
          double h[H > 0 ? H : 1];
          if (!pair_state(pv, b, r3, rot, i, neighbors(k), s)) {
            // Contact ended (or never began): its history is forgotten. Most such slots are
            // already zero; reading is cheaper than rewriting them every step.
            if constexpr (H > 0) {
              bool stale = false;
              for (int c = 0; c < H; ++c) stale = stale || history(k, c) != 0.0;
              if (stale)
                for (int c = 0; c < H; ++c) history(k, c) = 0.0;
            }
            continue;
          }
          if constexpr (H > 0)
            for (int c = 0; c < H; ++c) h[c] = history(k, c);
          PairForce out;
          m.evaluate(s, dt, h, out);
          if constexpr (H > 0)
            for (int c = 0; c < H; ++c) history(k, c) = h[c];
          for (int d = 0; d < 3; ++d) fi[d] += out.f[d];
          if (rot)
            for (int d = 0; d < 3; ++d) qi[d] += out.q[d];
        }
        for (int d = 0; d < 3; ++d) f(i, d) = fi[d];
        if (rot)
          for (int d = 0; d < 3; ++d) torque(i, d) = qi[d];
      });
}

}  // namespace granular
