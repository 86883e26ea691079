// Contact and background-damping forces: one generic loop over the neighbour list,
// templated on the contact model (the model struct holds the physics of one pair).
#pragma once
#include <Kokkos_Core.hpp>

#include "core/box.hpp"
#include "core/particles.hpp"
#include "kernels/neighbor_list.hpp"

namespace granular {

struct Damping {
  double translational = 0.0;  // gamma_b: f = -gamma_b (v - v_affine)
  double rotational = 0.0;     // gamma_br
};

// Velocities are stored relative to the affine flow of the deforming box (the box moves
// particles affinely in the strain kernel), so background damping acts on v directly and
// the contact dashpot adds the affine relative velocity rate * r_ij of the pair.
template <class ExecSpace, class Model>
void compute_forces(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                    const PeriodicBox& box, const Model& model, const Damping& damping,
                    const double strain_rate[3]) {
  auto x = p.x, v = p.v, f = p.f;
  auto radius = p.radius;
  auto offsets = nl.offsets(), neighbors = nl.neighbors();
  const PeriodicBox b = box;
  const Model m = model;
  const double gb = damping.translational;
  const double ex = strain_rate[0], ey = strain_rate[1], ez = strain_rate[2];
  Kokkos::parallel_for(
      "dem::compute_forces::linear_normal", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i) {
        const double xi = x(i, 0), yi = x(i, 1), zi = x(i, 2), ai = radius(i);
        const double vxi = v(i, 0), vyi = v(i, 1), vzi = v(i, 2);
        double fx = -gb * vxi, fy = -gb * vyi, fz = -gb * vzi;
        for (int k = offsets(i); k < offsets(i + 1); ++k) {
          const int j = neighbors(k);
          const double rx = b.min_image(xi - x(j, 0), 0);
          const double ry = b.min_image(yi - x(j, 1), 1);
          const double rz = b.min_image(zi - x(j, 2), 2);
          const double sum = ai + radius(j);
          const double r2 = rx * rx + ry * ry + rz * rz;
          if (r2 >= sum * sum) continue;  // reject before the sqrt
          const double r = Kokkos::Experimental::sqrt(r2);
          const double inv = 1.0 / r;
          const double nx = rx * inv, ny = ry * inv, nz = rz * inv;
          const double delta = sum - r;
          const double dvx = vxi - v(j, 0) + ex * rx;
          const double dvy = vyi - v(j, 1) + ey * ry;
          const double dvz = vzi - v(j, 2) + ez * rz;
          const double delta_dot = -(dvx * nx + dvy * ny + dvz * nz);
          const double fn = m.force(delta, delta_dot);
          fx += fn * nx;
          fy += fn * ny;
          fz += fn * nz;
        }
        f(i, 0) = fx;
        f(i, 1) = fy;
        f(i, 2) = fz;
      });
}

}  // namespace granular
