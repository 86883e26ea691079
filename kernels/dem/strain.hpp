// Homogeneous strain-rate deformation of the periodic box: box edges and particle
// positions are scaled together (affine motion), L <- L (1 + rate dt), about the box's
// lower corner. The neighbour list's reference positions move with them so the skin
// criterion sees only the non-affine motion.
#pragma once
#include <Kokkos_Core.hpp>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"

namespace granular {

template <class ExecSpace>
void apply_affine_strain(const Particles<ExecSpace>& p,
                         const typename Particles<ExecSpace>::vec_view& x_ref, PeriodicBox& box,
                         const double rate[3], double dt) {
  const double sx = 1.0 + rate[0] * dt, sy = 1.0 + rate[1] * dt, sz = 1.0 + rate[2] * dt;
  const double lx = box.lo[0], ly = box.lo[1], lz = box.lo[2];
  auto x = p.x;
  Kokkos::parallel_for(
      "dem::AffineStrain::scale", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i) {
        x(i, 0) = lx + (x(i, 0) - lx) * sx;
        x(i, 1) = ly + (x(i, 1) - ly) * sy;
        x(i, 2) = lz + (x(i, 2) - lz) * sz;
        x_ref(i, 0) = lx + (x_ref(i, 0) - lx) * sx;
        x_ref(i, 1) = ly + (x_ref(i, 1) - ly) * sy;
        x_ref(i, 2) = lz + (x_ref(i, 2) - lz) * sz;
      });
  box.len[0] *= sx;
  box.len[1] *= sy;
  box.len[2] *= sz;
}

}  // namespace granular
