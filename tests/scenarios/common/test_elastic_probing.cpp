// Elastic probing against the exact moduli of a simple cubic lattice with nearest-neighbour
// linear springs k at spacing a (no non-affine relaxation by symmetry). With a pre-stress
// (initial overlap d0, force k d0) the static stress sigma = r f / V gives
//   K = k/(3a) (1 + 2 d0/a),  G = (C11 - C12)/2 = k/(2a) (1 - d0/a),  M = C11 = k/a,
// and M = K + 4G/3 holds exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "kernels/contact/contact_model.hpp"
#include "scenarios/common/element_test.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

// The 6 x 6 x 6 simple cubic lattice (spacing a = 1, radius 0.502 a: overlap 0.004 a) of
// frictionless linear springs k = 2e3, with light background damping.
constexpr double kA = 1.0, kK = 2.0e3, kRadius = 0.502;
template <class Exec>
DemSystem<Exec, FrictionlessLinear> cubic_lattice() {
  const int m = 6;
  HostParticles h;
  h.resize(m * m * m);
  for (int i = 0; i < m * m * m; ++i) {
    h.x[i] = (i % m + 0.5) * kA, h.y[i] = ((i / m) % m + 0.5) * kA,
    h.z[i] = (i / (m * m) + 0.5) * kA;
    h.radius[i] = kRadius * kA, h.density[i] = 1.0;
  }
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.len[d] = m * kA;
  DemParams prm;
  prm.dt = 1e-3, prm.skin = 0.05, prm.damping.translational = 1.0;
  return DemSystem<Exec, FrictionlessLinear>(Particles<Exec>::from_host(h), box,
                                             frictionless_linear(kK, 0.0), prm);
}

template <class T>
class ProbingTest : public ::testing::Test {};
TYPED_TEST_SUITE(ProbingTest, granular::testing::ExecSpaces);

TYPED_TEST(ProbingTest, SimpleCubicLatticeModuliMatchTheExactSpringNetwork) {
  using Exec = TypeParam;
  const double a = kA, k = kK;
  auto sys = cubic_lattice<Exec>();
  double residual = 1;
  const Moduli mod = probe_moduli(sys, 1e-6, 200, 50, &residual);
  EXPECT_LT(std::fabs(residual), 1e-6);  // reversing the strain restores the stress
  const double d0 = 2 * kRadius * a - a;
  EXPECT_NEAR(mod.K / (k / (3 * a) * (1 + 2 * d0 / a)), 1.0, 1e-5);
  EXPECT_NEAR(mod.G / (k / (2 * a) * (1 - d0 / a)), 1.0, 1e-5);
  EXPECT_NEAR(mod.M / (k / a), 1.0, 1e-5);
  EXPECT_NEAR(mod.M / (mod.K + 4.0 / 3.0 * mod.G), 1.0, 1e-5);
  EXPECT_NEAR(mod.K_n, mod.K, 1e-9 * mod.K);  // frictionless: all normal
  EXPECT_EQ(mod.K_t, 0.0);
  // The lattice deforms affinely by symmetry: no non-affine fluctuation in any mode.
  EXPECT_LT(mod.eta_K, 1e-6);
  EXPECT_LT(mod.eta_G, 1e-6);
  EXPECT_LT(mod.eta_M, 1e-6);
}

// Reversibility on the same lattice: a small pre-strain is undone exactly (the modulus of the
// first reversal step is the elastic one), while a pure shear of 1e-2 stretches the y bonds
// open (their overlap is only 0.004 a): reversing it, only the x bonds carry the change, and
// the unloading shear modulus is that of the x springs alone: with s_xx = k d / (a_y a_z)
// (bond overlap d = 2R - a_x, box edges per particle a_x, a_y, a_z) and the shear measure
// d(s_xx - s_yy) / (2 d(e_x - e_y)), G_unload = k (a_x - d) / (4 a_y a_z), about k/(4a).
// The frictionless lattice closes its bonds again on the way back, so even then no stress is
// left after the whole reversal.
TYPED_TEST(ProbingTest, PrestrainIsUndoneAndAnOpenedLatticeUnloadsOnItsRemainingBonds) {
  using Exec = TypeParam;
  const double a = kA, k = kK;
  auto make = [] { return cubic_lattice<Exec>(); };
  const double d0 = 2 * kRadius * a - a;
  const double G0 = k / (2 * a) * (1 - d0 / a), K0 = k / (3 * a) * (1 + 2 * d0 / a);
  {
    auto sys = make();
    const Reversibility r =
        probe_reversibility(sys, kPureShear, 1e-4, 1e-6, 2000, 200, 1000, 1e-10, 1000);
    EXPECT_NEAR(r.loading / G0, 1.0, 2e-3);
    EXPECT_NEAR(r.unloading / G0, 1.0, 2e-3);
    EXPECT_LT(std::fabs(r.residual), 1e-4);
  }
  {
    auto sys = make();
    const Reversibility r =
        probe_reversibility(sys, kIsotropic, 1e-4, 1e-6, 2000, 200, 1000, 1e-10, 1000);
    EXPECT_NEAR(r.unloading / K0, 1.0, 2e-3);
    EXPECT_LT(std::fabs(r.residual), 1e-4);
  }
  {
    auto sys = make();
    const Reversibility r =
        probe_reversibility(sys, kPureShear, 1e-2, 1e-6, 8000, 200, 2000, 1e-10, 1000);
    const double ax = a * std::exp(-1e-2), ay = a * std::exp(1e-2), dx = 2 * kRadius * a - ax;
    EXPECT_NEAR(r.unloading / (k * (ax - dx) / (4 * ay * a)), 1.0, 1e-3);
    EXPECT_LT(r.loading / G0, 0.9);  // the secant modulus over the opening is lower too
    EXPECT_LT(std::fabs(r.residual), 1e-3);
  }
}
