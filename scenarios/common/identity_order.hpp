// The one gather of a system's particles into identity order on the host: row k holds the
// particle of identity k (the order the particles were given in), whatever order the engine
// keeps them in memory for locality. Saved states (write_state), the snapshot series' frames,
// saved configurations and resumed runs all take their rows from it, so they agree on which
// particle is particle k. Values are copied, never computed: every writer's bits are the
// system's.
#pragma once
#include <Kokkos_Core.hpp>
#include <string>
#include <vector>

#include "core/dem/host_particles.hpp"
#include "core/run/error.hpp"

namespace granular {

struct ParticleRows {
  int n = 0;
  std::vector<double> position, velocity, angular_velocity, force;  // 3 per row
  std::vector<double> radius, mass;
  std::vector<int> species;
};

// `p`: a Particles of any memory space. Identities that are not 0 .. n - 1, each once (a
// damaged saved state), are an InputError.
template <class P>
ParticleRows gather_by_identity(const P& p) {
  const auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  const auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  const auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.w);
  const auto f = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.f);
  const auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.radius);
  const auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  const auto s = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.species);
  const auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.id);
  const int n = p.n;
  ParticleRows rows;
  rows.n = n;
  for (auto* c : {&rows.position, &rows.velocity, &rows.angular_velocity, &rows.force})
    c->assign(3 * static_cast<size_t>(n), 0.0);
  rows.radius.assign(n, 0.0), rows.mass.assign(n, 0.0), rows.species.assign(n, 0);
  std::vector<char> seen(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    const int k = id(i);
    if (k < 0 || k >= n || seen[k])
      throw InputError("particle identities are not 0 .. " + std::to_string(n - 1) +
                       ", each once (identity " + std::to_string(k) + " at row " +
                       std::to_string(i) + ")");
    seen[k] = 1;
    for (int d = 0; d < 3; ++d) {
      rows.position[3 * k + d] = x(i, d), rows.velocity[3 * k + d] = v(i, d);
      rows.angular_velocity[3 * k + d] = w(i, d), rows.force[3 * k + d] = f(i, d);
    }
    rows.radius[k] = r(i), rows.mass[k] = m(i), rows.species[k] = s(i);
  }
  return rows;
}

// The rows as host particles (positions, velocities, spins, radii, species), particle k of
// density `density(k)`: what a system is made from again.
template <class Density>
HostParticles host_particles(const ParticleRows& g, Density density) {
  HostParticles h;
  h.resize(g.n);
  for (int k = 0; k < g.n; ++k) {
    h.x[k] = g.position[3 * k], h.y[k] = g.position[3 * k + 1], h.z[k] = g.position[3 * k + 2];
    h.vx[k] = g.velocity[3 * k], h.vy[k] = g.velocity[3 * k + 1];
    h.vz[k] = g.velocity[3 * k + 2];
    h.wx[k] = g.angular_velocity[3 * k], h.wy[k] = g.angular_velocity[3 * k + 1];
    h.wz[k] = g.angular_velocity[3 * k + 2];
    h.radius[k] = g.radius[k], h.density[k] = density(k), h.species[k] = g.species[k];
  }
  return h;
}

}  // namespace granular
