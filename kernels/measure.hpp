// Micro-to-macro measurements of a DEM state: energies, static stress, pressure,
// coordination (with rattlers), volume fraction, largest overlap. Per-particle values
// are summed with deterministic_column_sums, so the numbers do not depend on threads.
#pragma once
#include <Kokkos_Core.hpp>
#include <array>

#include "core/box.hpp"
#include "core/particles.hpp"
#include "kernels/deterministic_sum.hpp"
#include "kernels/neighbor_list.hpp"

namespace granular {

struct Measurements {
  double ekin = 0;        // translational + rotational kinetic energy
  double epot = 0;        // elastic energy stored in contacts
  double stress[6] = {};  // xx yy zz xy xz yz; static (contact) part, positive in compression
  double pressure = 0;    // tr(stress)/3
  double contacts = 0;    // number of contacts (pairs)
  double z = 0;           // 2 contacts / N
  double z_corrected = 0; // contacts per non-rattler, counted on non-rattlers only
  double rattlers = 0;    // particles with fewer contacts than the threshold
  double phi = 0;         // volume fraction (overlaps ignored)
  double max_overlap = 0; // largest delta / min(a_i, a_j)
  double volume = 0;
};

template <class ExecSpace, class Model>
Measurements measure(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                     const PeriodicBox& box, const Model& model, int rattler_threshold,
                     double particle_volume) {
  constexpr int NC = 11;
  using mem = typename ExecSpace::memory_space;
  Kokkos::View<double**, Kokkos::LayoutRight, mem> per("measure::per_particle", p.n, NC);
  auto x = p.x, v = p.v, w = p.w;
  auto radius = p.radius, mass = p.mass, inertia = p.inertia;
  auto offsets = nl.offsets(), neighbors = nl.neighbors();
  const PeriodicBox b = box;
  const Model m = model;
  const int thr = rattler_threshold;
  double max_overlap = 0.0;
  Kokkos::parallel_reduce(
      "dem::measure::per_particle", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i, double& mo) {
        double s[6] = {0, 0, 0, 0, 0, 0};
        double epot = 0.0;
        int c = 0;
        const double ai = radius(i);
        for (int k = offsets(i); k < offsets(i + 1); ++k) {
          const int j = neighbors(k);
          const double rx = b.min_image(x(i, 0) - x(j, 0), 0);
          const double ry = b.min_image(x(i, 1) - x(j, 1), 1);
          const double rz = b.min_image(x(i, 2) - x(j, 2), 2);
          const double sum = ai + radius(j);
          const double r2 = rx * rx + ry * ry + rz * rz;
          if (r2 >= sum * sum) continue;
          const double r = Kokkos::Experimental::sqrt(r2);
          const double delta = sum - r;
          // Elastic part only: the stress of a static packing; each pair is seen twice.
          const double fn = m.force(delta, 0.0);
          const double lf = 0.5 * fn / r;  // (r n) (fn n) / 2 = r r fn / (2 r)
          s[0] += lf * rx * rx, s[1] += lf * ry * ry, s[2] += lf * rz * rz;
          s[3] += lf * rx * ry, s[4] += lf * rx * rz, s[5] += lf * ry * rz;
          epot += 0.5 * m.energy(delta);
          ++c;
          const double amin = ai < radius(j) ? ai : radius(j);
          mo = delta / amin > mo ? delta / amin : mo;
        }
        const double v2 = v(i, 0) * v(i, 0) + v(i, 1) * v(i, 1) + v(i, 2) * v(i, 2);
        const double w2 = w(i, 0) * w(i, 0) + w(i, 1) * w(i, 1) + w(i, 2) * w(i, 2);
        per(i, 0) = 0.5 * mass(i) * v2 + 0.5 * inertia(i) * w2;
        per(i, 1) = epot;
        for (int q = 0; q < 6; ++q) per(i, 2 + q) = s[q];
        per(i, 8) = c;
        per(i, 9) = c >= thr ? 1.0 : 0.0;
        per(i, 10) = c >= thr ? c : 0.0;
      },
      Kokkos::Max<double>(max_overlap));
  const auto sums = deterministic_column_sums<NC, ExecSpace>(per, p.n);
  Measurements out;
  out.volume = box.volume();
  out.ekin = sums[0];
  out.epot = sums[1];
  for (int q = 0; q < 6; ++q) out.stress[q] = sums[2 + q] / out.volume;
  out.pressure = (out.stress[0] + out.stress[1] + out.stress[2]) / 3.0;
  out.contacts = sums[8] / 2.0;
  out.z = p.n > 0 ? sums[8] / p.n : 0.0;
  out.rattlers = p.n - sums[9];
  out.z_corrected = sums[9] > 0 ? sums[10] / sums[9] : 0.0;
  out.phi = particle_volume / out.volume;
  out.max_overlap = max_overlap;
  return out;
}

}  // namespace granular
