// The host kick-drift pass four particles at a time (KickDriftRows::run_avx2 in
// kernels/dem/integrator.hpp) against the particle-by-particle pass (run): the same bits of
// positions, velocities, forces, spins and torques, the same largest squared displacement and
// drift speed, for every combination of the pass's switches, with particles wrapped through
// periodic faces in both directions, displacements folded by the minimum image, a NaN
// velocity, and particle counts that leave a tail of one to three after the last whole four.
// And the pass written with Kokkos' loops (kick_drift_kokkos, the devices' pass) against
// kick_drift on every backend (the host rows on host backends): the same bits and the same
// maximum, wherever in the pass the largest displacement lies. And the packed records the pass
// writes for the frictional stream (KickDriftRows::pack): the bits it stores in the arrays.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/run/rng.hpp"
#include "kernels/dem/integrator.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::bitwise_equal;

namespace {

// (Host AVX builds only: elsewhere there is no four-particle pass to compare with.)
#if GRANULAR_HOST_AVX
struct Arrays {
  std::vector<double> x, v, f, w, q, mass, inertia, x_ref;
};

// n particles in a box of 10 x 10 x 10 from the origin; a third sit just inside a face and
// move out through it within the step, a few have reference positions across the box.
Arrays make_arrays(int n, unsigned seed) {
  Arrays a;
  for (auto* v : {&a.x, &a.v, &a.f, &a.w, &a.q, &a.x_ref}) v->resize(3 * n);
  a.mass.resize(n), a.inertia.resize(n);
  for (int i = 0; i < n; ++i) {
    Stream s(seed, i);
    a.mass[i] = s.uniform(0.5, 2.0), a.inertia[i] = s.uniform(0.05, 0.3);
    for (int d = 0; d < 3; ++d) {
      const int c = 3 * i + d;
      a.x[c] = s.uniform(0.0, 10.0);
      a.v[c] = s.uniform(-1.0, 1.0);
      if (i % 3 == 0) a.x[c] = (i % 2) ? 9.9999 : 1e-5, a.v[c] = (i % 2) ? 1.0 : -1.0;
      a.f[c] = s.uniform(-5.0, 5.0), a.w[c] = s.uniform(-2.0, 2.0), a.q[c] = s.uniform(-1.0, 1.0);
      // Six across the periodic x and z (folded to four), close across the walled y.
      const bool across = i % 7 == 0 && i % 3 != 0 && d != 1;
      a.x_ref[c] = a.x[c] + (across ? 6.0 : s.uniform(-0.01, 0.01));
    }
  }
  if (n > 5) a.v[3 * 5 + 1] = std::numeric_limits<double>::quiet_NaN();
  return a;
}

KickDriftRows rows_of(Arrays& a, bool pending, bool damp) {
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0.0, box.len[d] = 10.0, box.periodic[d] = d != 1;
  // (walls across y: no wrap, no folding there)
  DampingStart ds;
  ds.on = damp, ds.translational = 0.7, ds.rotational = 0.3;
  return KickDriftRows{a.x.data(), a.v.data(),    a.f.data(),       a.w.data(),
                       a.q.data(), a.mass.data(), a.inertia.data(), a.x_ref.data(),
                       box,        0.05,          pending,          ds};
}
#endif

template <bool Rotations, bool Speed>
void compare(int n, bool pending, bool damp) {
#if GRANULAR_HOST_AVX
  Arrays a = make_arrays(n, 31), b = make_arrays(n, 31);
  double va = 0.25, vb = 0.25;
  const double ma = rows_of(a, pending, damp).run<Rotations, Speed>(0, n, va);
  const double mb = rows_of(b, pending, damp).run_avx2<Rotations, Speed>(0, n, vb);
  const std::string what = "n " + std::to_string(n) + " pending " + std::to_string(pending) +
                           " damp " + std::to_string(damp);
  EXPECT_TRUE(bitwise_equal({ma}, {mb})) << what << ": " << ma << " " << mb;
  EXPECT_TRUE(bitwise_equal({va}, {vb})) << what << ": " << va << " " << vb;
  EXPECT_TRUE(bitwise_equal(a.x, b.x)) << what;
  EXPECT_TRUE(bitwise_equal(a.v, b.v)) << what;
  EXPECT_TRUE(bitwise_equal(a.f, b.f)) << what;
  EXPECT_TRUE(bitwise_equal(a.w, b.w)) << what;
  EXPECT_TRUE(bitwise_equal(a.q, b.q)) << what;
  if (Speed && n > 5) {
    EXPECT_TRUE(std::isnan(vb)) << "a NaN speed must reach the maximum";
  }
  if (n > 20) {  // two folded components: 2 x 4^2 = 32 (unfolded 72)
    EXPECT_GT(ma, 30.0);
    EXPECT_LT(ma, 36.0);
  }
#else
  (void)n, (void)pending, (void)damp;
#endif
}

// The pass writing the packed records (KickDriftRows::pack), four at a time or one by one:
// each record holds the bits the pass stored in the arrays (position, radius, velocity, mass,
// spin, a zero pad), and the arrays are those of the pass without records.
template <bool Rotations>
void compare_records(int n, bool avx2) {
#if GRANULAR_HOST_AVX
  Arrays a = make_arrays(n, 43), b = make_arrays(n, 43);
  std::vector<double> radius(n);
  for (int i = 0; i < n; ++i) radius[i] = 0.1 + 1e-3 * i;
  constexpr int S = ParticlePack::kStride;
  // 32-byte aligned, as the aligned loads of the stream want, and filled with NaN first.
  std::vector<double> store(S * n + 4, std::numeric_limits<double>::quiet_NaN());
  double* pack = store.data();
  while (reinterpret_cast<std::uintptr_t>(pack) % 32 != 0) ++pack;
  KickDriftRows plain = rows_of(a, true, true), packed = rows_of(b, true, true);
  packed.pack = pack, packed.radius = radius.data();
  double va = 0.0, vb = 0.0;
  const double ma =
      avx2 ? plain.run_avx2<Rotations, true>(0, n, va) : plain.run<Rotations, true>(0, n, va);
  const double mb =
      avx2 ? packed.run_avx2<Rotations, true>(0, n, vb) : packed.run<Rotations, true>(0, n, vb);
  const std::string what = "n " + std::to_string(n) + (avx2 ? " avx2" : " scalar");
  EXPECT_TRUE(bitwise_equal({ma, va}, {mb, vb})) << what;
  EXPECT_TRUE(bitwise_equal(a.x, b.x) && bitwise_equal(a.v, b.v) && bitwise_equal(a.f, b.f) &&
              bitwise_equal(a.w, b.w) && bitwise_equal(a.q, b.q))
      << what;
  std::vector<double> expect(S * n), got(pack, pack + S * n);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 4; ++d) {
      double* const r = expect.data() + S * i;
      r[d] = d < 3 ? b.x[3 * i + d] : radius[i];
      r[4 + d] = d < 3 ? b.v[3 * i + d] : b.mass[i];
      r[8 + d] = d < 3 ? b.w[3 * i + d] : 0.0;
    }
  EXPECT_TRUE(bitwise_equal(expect, got)) << what;
#else
  (void)n, (void)avx2;
#endif
}

}  // namespace

TEST(KickDriftTest, PackedRecordsHoldTheBitsThePassStoresInTheArrays) {
  for (int n : {1, 3, 4, 7, 64, 1029, 1031})
    for (bool avx2 : {false, true}) {
      if (avx2 && !cpu_has_avx2()) continue;
      compare_records<true>(n, avx2);
      compare_records<false>(n, avx2);
    }
}

TEST(KickDriftTest, FourParticlesAtATimeGiveTheBitsOfTheParticleByParticlePass) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "the processor has no AVX2";
  for (int n : {1, 3, 4, 7, 64, 1029, 1030, 1031})
    for (bool pending : {false, true})
      for (bool damp : {false, true}) {
        compare<false, false>(n, pending, damp);
        compare<false, true>(n, pending, damp);
        compare<true, false>(n, pending, damp);
        compare<true, true>(n, pending, damp);
      }
}

namespace {

template <class Exec>
std::vector<double> host_vec(const typename Particles<Exec>::vec_view& v) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  return std::vector<double>(h.data(), h.data() + h.size());
}

// n particles in a 10 x 10 x 10 box (periodic along x and z), a third about to leave through a
// face, every one's reference position drawn near it, a few across the box; the largest
// displacement belongs to the particle `far` (the last one of the pass unless told).
template <class Exec>
Particles<Exec> drifting(int n, int far, typename Particles<Exec>::vec_view& x_ref) {
  Particles<Exec> p(n);
  auto x = Kokkos::create_mirror_view(p.x), v = Kokkos::create_mirror_view(p.v);
  auto f = Kokkos::create_mirror_view(p.f), w = Kokkos::create_mirror_view(p.w);
  auto q = Kokkos::create_mirror_view(p.torque), r = Kokkos::create_mirror_view(x_ref);
  auto m = Kokkos::create_mirror_view(p.mass), in = Kokkos::create_mirror_view(p.inertia);
  for (int i = 0; i < n; ++i) {
    Stream s(77, i);
    m(i) = s.uniform(0.5, 2.0), in(i) = s.uniform(0.05, 0.3);
    for (int d = 0; d < 3; ++d) {
      x(i, d) = s.uniform(0.0, 10.0), v(i, d) = s.uniform(-1.0, 1.0);
      if (i % 3 == 0) x(i, d) = (i % 2) ? 9.9999 : 1e-5, v(i, d) = (i % 2) ? 1.0 : -1.0;
      f(i, d) = s.uniform(-5.0, 5.0), w(i, d) = s.uniform(-2.0, 2.0);
      q(i, d) = s.uniform(-1.0, 1.0);
      r(i, d) = x(i, d) + s.uniform(-0.01, 0.01);
      if (i % 7 == 0 && i % 3 != 0 && d != 1) r(i, d) = x(i, d) + 6.0;  // folded to 4
    }
  }
  for (int d = 0; d < 3; ++d) r(far, d) = x(far, d) + (d == 1 ? 3.0 : 4.5);
  Kokkos::deep_copy(p.x, x), Kokkos::deep_copy(p.v, v), Kokkos::deep_copy(p.f, f);
  Kokkos::deep_copy(p.w, w), Kokkos::deep_copy(p.torque, q), Kokkos::deep_copy(x_ref, r);
  Kokkos::deep_copy(p.mass, m), Kokkos::deep_copy(p.inertia, in);
  return p;
}

}  // namespace

template <class T>
class KickDriftKokkosTest : public ::testing::Test {};
TYPED_TEST_SUITE(KickDriftKokkosTest, granular::testing::ExecSpaces);

TYPED_TEST(KickDriftKokkosTest, DevicePassGivesTheBitsAndMaximumOfTheBackendsPass) {
  using Exec = TypeParam;
  using P = Particles<Exec>;
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0.0, box.len[d] = 10.0, box.periodic[d] = d != 1;
  DampingStart ds;
  ds.translational = 0.7, ds.rotational = 0.3;
  // The farthest particle first, inside, last; counts with and without a tail of four.
  for (const int n : {1, 127, 128, 129, 1000, 5003})
    for (const int far : {0, n / 2, n - 1})
      for (const bool pending : {false, true})
        for (const bool damp : {false, true}) {
          ds.on = damp;
          typename P::vec_view ra("ra", n), rb("rb", n);
          P a = drifting<Exec>(n, far, ra), b = drifting<Exec>(n, far, rb);
          const double ma = kick_drift<true>(a, box, ra, 0.05, pending, ds);
          const double mb = kick_drift_kokkos<true>(b, box, rb, 0.05, pending, ds);
          const std::string what = "n " + std::to_string(n) + " far " + std::to_string(far) +
                                   " pending " + std::to_string(pending) + " damp " +
                                   std::to_string(damp);
          EXPECT_TRUE(bitwise_equal({ma}, {mb})) << what << ": " << ma << " " << mb;
          // The far particle's (about 2 x 4.5^2 + 3^2, give or take its drift), where every
          // other's is below 2 x 4.1^2.
          EXPECT_GT(ma, 45.0) << what;
          EXPECT_LT(ma, 56.0) << what;
          EXPECT_TRUE(bitwise_equal(host_vec<Exec>(a.x), host_vec<Exec>(b.x))) << what;
          EXPECT_TRUE(bitwise_equal(host_vec<Exec>(a.v), host_vec<Exec>(b.v))) << what;
          EXPECT_TRUE(bitwise_equal(host_vec<Exec>(a.f), host_vec<Exec>(b.f))) << what;
          EXPECT_TRUE(bitwise_equal(host_vec<Exec>(a.w), host_vec<Exec>(b.w))) << what;
          EXPECT_TRUE(bitwise_equal(host_vec<Exec>(a.torque), host_vec<Exec>(b.torque))) << what;
        }
}
