// Particle store: one Kokkos View per field (structure of arrays), templated on the
// execution space so the same store lives in host or device memory.
#pragma once
#include <Kokkos_Core.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "core/dem/host_particles.hpp"
#include "core/run/error.hpp"

namespace granular {

// Memory a DEM particle costs with its neighbour entries and contact histories, an upper
// estimate used to refuse absurd particle counts before anything is allocated.
constexpr double kDemBytesPerParticle = 4096;

// a <- a(order(i)) row by row, for rank-1 and (n x 3) views.
template <class ExecSpace, class V, class Order>
void gather_rows(V& a, const Order& order, int n) {
  V b(a.label(), n);
  auto src = a;
  Kokkos::parallel_for(
      "particles::gather_rows", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const int i) {
        const int o = order(i);
        (void)b.extent(0), (void)src.extent(0);  // nvcc: capture outside the constexpr-if
        if constexpr (V::rank == 2) {
          for (int d = 0; d < 3; ++d) b(i, d) = src(o, d);
        } else {
          b(i) = src(o);
        }
      });
  a = b;
}

template <class ExecSpace>
struct Particles {
  using execution_space = ExecSpace;
  using memory_space = typename ExecSpace::memory_space;
  using vec_view = Kokkos::View<double* [3], memory_space>;
  using scalar_view = Kokkos::View<double*, memory_space>;
  using int_view = Kokkos::View<int*, memory_space>;

  int n = 0;
  vec_view x, v, w, f, torque;  // position, velocity, angular velocity, force, torque
  scalar_view radius, mass, inertia;
  int_view species;
  int_view id;  // stable identity (input order), survives any reordering of the arrays

  Particles() = default;
  Particles(const Particles&) = default;
  Particles& operator=(const Particles&) = default;
  // A real move. Kokkos 3.4's View copies when moved (its tracker declares no move
  // constructor), so a defaulted move would leave the source holding every array: a system
  // made from std::move(particles) would keep the caller's arrays alive beside its own
  // (the first rebuild permutes into new ones), ~150 B per particle of peak memory.
  Particles(Particles&& o) noexcept : Particles(static_cast<const Particles&>(o)) { o.release(); }
  Particles& operator=(Particles&& o) noexcept {
    if (this != &o) {
      *this = static_cast<const Particles&>(o);
      o.release();
    }
    return *this;
  }
  void release() {
    n = 0;
    x = v = w = f = torque = vec_view();
    radius = mass = inertia = scalar_view();
    species = id = int_view();
  }
  explicit Particles(int n_) : n(n_) {
    x = vec_view("particles::x", n);
    v = vec_view("particles::v", n);
    w = vec_view("particles::w", n);
    f = vec_view("particles::f", n);
    torque = vec_view("particles::torque", n);
    radius = scalar_view("particles::radius", n);
    mass = scalar_view("particles::mass", n);
    inertia = scalar_view("particles::inertia", n);
    species = int_view("particles::species", n);
    id = int_view("particles::id", n);
  }

  // Reorders every per-particle field: new particle i is old particle order(i).
  void permute(const int_view& order) {
    for (vec_view* a : {&x, &v, &w, &f, &torque}) gather_rows<ExecSpace>(*a, order, n);
    gather_rows<ExecSpace>(radius, order, n);
    gather_rows<ExecSpace>(mass, order, n);
    gather_rows<ExecSpace>(inertia, order, n);
    gather_rows<ExecSpace>(species, order, n);
    gather_rows<ExecSpace>(id, order, n);
  }

  static Particles from_host(const HostParticles& h) {
    const int n = h.size();
    Particles p(n);
    auto x = Kokkos::create_mirror_view(p.x);
    auto v = Kokkos::create_mirror_view(p.v);
    auto w = Kokkos::create_mirror_view(p.w);
    auto r = Kokkos::create_mirror_view(p.radius);
    auto m = Kokkos::create_mirror_view(p.mass);
    auto in = Kokkos::create_mirror_view(p.inertia);
    auto s = Kokkos::create_mirror_view(p.species);
    auto id = Kokkos::create_mirror_view(p.id);
    for (int i = 0; i < n; ++i) {
      x(i, 0) = h.x[i], x(i, 1) = h.y[i], x(i, 2) = h.z[i];
      v(i, 0) = h.vx[i], v(i, 1) = h.vy[i], v(i, 2) = h.vz[i];
      // Generators that fill only positions and velocities leave the spins at rest.
      const bool spins = h.wx.size() == h.radius.size();
      w(i, 0) = spins ? h.wx[i] : 0.0, w(i, 1) = spins ? h.wy[i] : 0.0;
      w(i, 2) = spins ? h.wz[i] : 0.0;
      r(i) = h.radius[i];
      if (!(h.radius[i] > 0) || !(h.density[i] > 0))
        throw InputError("particle " + std::to_string(i) + " has a non-positive radius or density");
      m(i) = h.density[i] * 4.0 / 3.0 * M_PI * h.radius[i] * h.radius[i] * h.radius[i];
      in(i) = 0.4 * m(i) * h.radius[i] * h.radius[i];
      s(i) = h.species[i];
      id(i) = i;
    }
    Kokkos::deep_copy(p.x, x);
    Kokkos::deep_copy(p.v, v);
    Kokkos::deep_copy(p.w, w);
    Kokkos::deep_copy(p.radius, r);
    Kokkos::deep_copy(p.mass, m);
    Kokkos::deep_copy(p.inertia, in);
    Kokkos::deep_copy(p.species, s);
    Kokkos::deep_copy(p.id, id);
    return p;
  }
};

}  // namespace granular
