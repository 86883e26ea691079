// Cuboid box, periodic along each axis unless that axis is closed by walls: minimum-image
// convention and re-entry of particles on the periodic axes only. On a walled axis the box
// is just the region the cell grid covers (particles may overlap the walls slightly).
#pragma once
#include <Kokkos_Core.hpp>

namespace granular {

struct PeriodicBox {
  double lo[3] = {0, 0, 0};
  double len[3] = {1, 1, 1};
  bool periodic[3] = {true, true, true};

  bool fully_periodic() const { return periodic[0] && periodic[1] && periodic[2]; }

  KOKKOS_INLINE_FUNCTION double volume() const { return len[0] * len[1] * len[2]; }

  // Shortest periodic image of a separation along axis d. Valid for |dx| < 1.5 L, which
  // holds for particles that are wrapped every step.
  KOKKOS_INLINE_FUNCTION double min_image(double dx, int d) const {
    const double l = len[d];
    if (!periodic[d]) return dx;
    if (dx > 0.5 * l)
      dx -= l;
    else if (dx < -0.5 * l)
      dx += l;
    return dx;
  }

  // Re-entry through the opposite face.
  KOKKOS_INLINE_FUNCTION double wrap(double x, int d) const {
    const double l = len[d];
    if (!periodic[d]) return x;
    if (x >= lo[d] + l)
      x -= l;
    else if (x < lo[d])
      x += l;
    return x;
  }
};

}  // namespace granular
