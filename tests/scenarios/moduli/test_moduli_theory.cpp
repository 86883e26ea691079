// EMT and fluctuation theory against values worked out by hand from the formulas of
// docs/model_dem.md §9 (phi = 0.64, Z = 6, D = 1.15, k_t/k_n = 0.8, chi from the closure).
#include <gtest/gtest.h>

#include <cmath>

#include "scenarios/moduli/moduli_theory.hpp"

using granular::moduli_theory;
using granular::TheoryInput;

TEST(ModuliTheory, EffectiveMediumAndFluctuationTheoryMatchHandValues) {
  TheoryInput in;
  in.phi = 0.64, in.z = 6, in.D = 1.15, in.kt_kn = 0.8;
  const auto r = moduli_theory(in);
  // By hand: phi Z D = 4.416; chi = 1/(0.64*6) = 0.2604167.
  EXPECT_NEAR(r.chi, 0.26041667, 1e-8);
  EXPECT_NEAR(r.K_emt, 4.416 / (3 * M_PI), 1e-12);        // 0.468557
  EXPECT_NEAR(r.G_emt, 2.2 * 4.416 / (5 * M_PI), 1e-12);  // 0.618495
  // rho = (4/24)(1/6 - 1/36) + chi/8 = 0.0231481 + 0.0325521 = 0.0557002
  EXPECT_NEAR(r.rho, 0.05570023, 1e-8);
  // zeta = -(12/156)(1 - 24/78) - (261/676) chi = -0.0532544 - 0.1005455 = -0.1537999
  EXPECT_NEAR(r.zeta, -0.15379993, 1e-8);
  // second ring factor 1 - 2 rho + 2 zeta = 0.5809997
  EXPECT_NEAR(r.rho_s, 0.05570023 * 0.58099968, 1e-8);
  EXPECT_NEAR(r.zeta_s, -0.15379993 * 0.58099968, 1e-8);
  // First ring: K = (1 - 2 rho) 4.416/(3 pi) = 0.8885995 * 0.4685567
  EXPECT_NEAR(r.K_ft1, 0.88859954 * 4.416 / (3 * M_PI), 1e-8);
  // G = (1 - 2 rho) 4.416/(5 pi) + 1.2 (1 - 2 rho + 2 zeta) 4.416/(5 pi)
  EXPECT_NEAR(r.G_ft1, (0.88859954 + 1.2 * 0.58099968) * 4.416 / (5 * M_PI), 1e-7);
  // Second ring: rho + rho* = 0.0557002 * 1.5809997 = 0.0880620
  EXPECT_NEAR(r.K_ft2, (1 - 2 * 0.08806205) * 4.416 / (3 * M_PI), 1e-7);
  // Theories are ordered: fluctuations soften the affine estimate.
  EXPECT_LT(r.K_ft2, r.K_ft1);
  EXPECT_LT(r.K_ft1, r.K_emt);
}

TEST(ModuliTheory, MeasuredChiReplacesClosure) {
  TheoryInput in;
  in.phi = 0.7, in.z = 7, in.chi = 0.1, in.D = 1.15;
  const auto r = moduli_theory(in);
  EXPECT_DOUBLE_EQ(r.chi, 0.1);
  EXPECT_NEAR(r.rho, (22 - 21.0) / 24 * (1.0 / 7 - 1.0 / 49) + 0.1 / 8, 1e-14);
  EXPECT_DOUBLE_EQ(r.G_emt, 0.7 * 7 * 1.15 / (5 * M_PI));  // k_t = 0
}

// The default size moment is the formula's own value for the shipped size range (d uniform in
// [1, 3]): dbar <d^2>/<d^3> = 2 (13/3) / 10, not the reciprocal 1.15 the source quotes.
TEST(ModuliTheory, DefaultSizeMomentIsTheFormulasValueForDiametersUniformFromOneToThree) {
  const double mean = 2.0, second = (27.0 - 1.0) / (3 * 2.0), third = (81.0 - 1.0) / (4 * 2.0);
  EXPECT_NEAR(TheoryInput{}.D, mean * second / third, 1e-15);
}

// A packing without contacts (Z = 0, every particle a rattler) has no theory: its values are
// NaN ("not applicable"), never inf, which used to reach results.h5.
TEST(ModuliTheory, NoContactsGiveNotApplicableNeverInfinite) {
  TheoryInput in;
  in.phi = 0.6, in.z = 0, in.kt_kn = 0.5;
  const auto r = moduli_theory(in);
  for (double v : {r.chi, r.rho, r.zeta, r.rho_s, r.zeta_s, r.K_emt, r.G_emt, r.K_ft1, r.G_ft1,
                   r.K_ft2, r.G_ft2})
    EXPECT_FALSE(std::isinf(v)) << v;
}
