// The one gather into identity order (scenarios/common/identity_order.hpp): after the arrays
// are reordered, as a locality sort does, row k holds every field of the particle of identity
// k, bit for bit; identities that are not a permutation of 0 .. n - 1 are refused.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <cstring>

#include "core/dem/particles.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/identity_order.hpp"

using namespace granular;
using Exec = Kokkos::DefaultExecutionSpace;

namespace {
Particles<Exec> shuffled(int n) {
  HostParticles h;
  h.resize(n);
  for (int i = 0; i < n; ++i) {
    h.x[i] = 1.0 / (i + 3), h.y[i] = 2.0 + i, h.z[i] = -0.1 * i;
    h.vx[i] = 0.7 * i, h.vy[i] = 1.0 / (i + 7), h.vz[i] = 3.0;
    h.wx[i] = -0.3 * i, h.wy[i] = 0.01, h.wz[i] = 1.0 / (i + 11);
    h.radius[i] = 0.5 + 0.01 * i, h.density[i] = 1000.0 + i, h.species[i] = i % 4;
  }
  auto p = Particles<Exec>::from_host(h);
  Particles<Exec>::int_view order("order", n);
  auto oh = Kokkos::create_mirror_view(order);
  for (int i = 0; i < n; ++i) oh(i) = (5 * i + 2) % n;  // a permutation for n = 9
  Kokkos::deep_copy(order, oh);
  p.permute(order);
  return p;
}
}  // namespace

TEST(IdentityOrder, RowKHoldsEveryFieldOfIdentityKAfterReordering) {
  const int n = 9;
  const auto p = shuffled(n);
  // Forces are not set by from_host: give each particle its own, by its identity.
  {
    auto f = Kokkos::create_mirror_view(p.f);
    auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.id);
    for (int i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) f(i, d) = 100.0 * id(i) + d;
    Kokkos::deep_copy(p.f, f);
  }
  const ParticleRows rows = gather_by_identity(p);
  ASSERT_EQ(rows.n, n);
  const auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  const auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  const auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.w);
  const auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.radius);
  const auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  const auto s = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.species);
  const auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.id);
  int moved = 0;
  for (int i = 0; i < n; ++i) {
    const int k = id(i);
    moved += k != i;
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(rows.position[3 * k + d], x(i, d));
      EXPECT_EQ(rows.velocity[3 * k + d], v(i, d));
      EXPECT_EQ(rows.angular_velocity[3 * k + d], w(i, d));
      EXPECT_EQ(rows.force[3 * k + d], 100.0 * k + d);
    }
    EXPECT_EQ(rows.radius[k], r(i));
    EXPECT_EQ(rows.mass[k], m(i));
    EXPECT_EQ(rows.species[k], s(i));
    EXPECT_EQ(rows.radius[k], 0.5 + 0.01 * k);  // the value identity k was created with
  }
  EXPECT_GT(moved, 0) << "the arrays must have been reordered for the test to mean anything";
}

TEST(IdentityOrder, IdentitiesThatAreNotAPermutationAreRefused) {
  const int n = 9;
  auto p = shuffled(n);
  auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.id);
  id(3) = id(4);  // one identity twice, another missing
  Kokkos::deep_copy(p.id, id);
  EXPECT_THROW(gather_by_identity(p), InputError);
  id(3) = n;  // out of range
  Kokkos::deep_copy(p.id, id);
  EXPECT_THROW(gather_by_identity(p), InputError);
}
