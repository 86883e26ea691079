// The host kick-drift pass four particles at a time (KickDriftRows::run_avx2 in
// kernels/integrator.hpp) against the particle-by-particle pass (run): the same bits of
// positions, velocities, forces, spins and torques, the same largest squared displacement and
// drift speed, for every combination of the pass's switches, with particles wrapped through
// periodic faces in both directions, displacements folded by the minimum image, a NaN
// velocity, and particle counts that leave a tail of one to three after the last whole four.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/rng.hpp"
#include "kernels/integrator.hpp"
#include "test_support.hpp"

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

}  // namespace

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
