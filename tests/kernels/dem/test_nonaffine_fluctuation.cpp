// Non-affine displacement fluctuation (docs/model_dem.md §7): for each contact, the relative
// displacement minus its affine part eps l, normalised by |eps l|. Checked on a chain of
// contacts with a hand-made displacement field, and zero for an affine deformation.
#include <gtest/gtest.h>

#include <cmath>

#include "kernels/dem/measure.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

template <class T>
class NonAffineTest : public ::testing::Test {};
TYPED_TEST_SUITE(NonAffineTest, granular::testing::ExecSpaces);

// Three spheres in a row along x, touching 0-1 through the periodic face and 1-2 inside.
TYPED_TEST(NonAffineTest, FluctuationOfAHandMadeDisplacementFieldMatchesItsDefinition) {
  using Exec = TypeParam;
  const double gap = 0.99;  // centre distance, radius 0.5: overlapping
  HostParticles h;
  h.resize(3);
  const double x[3] = {9.7, 9.7 + gap - 10.0, 9.7 + 2 * gap - 10.0};
  for (int i = 0; i < 3; ++i) h.x[i] = x[i], h.y[i] = 2.0, h.z[i] = 2.0;
  for (int i = 0; i < 3; ++i) h.radius[i] = 0.5, h.density[i] = 1.0;
  PeriodicBox box0;
  box0.len[0] = 10.0, box0.len[1] = 4.0, box0.len[2] = 4.0;
  auto p = Particles<Exec>::from_host(h);
  const auto x0 = positions_by_id(p);

  // Deform the box by eps = (e, 0, 0) about its lower corner, move everyone affinely, and
  // add a non-affine displacement u to particle 1 only.
  const double e = -1e-3, u[3] = {2e-4, 1e-4, 0.0};
  PeriodicBox box = box0;
  box.len[0] *= 1 + e;
  auto hx = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  for (int i = 0; i < 3; ++i) hx(i, 0) = box.lo[0] + (hx(i, 0) - box.lo[0]) * (1 + e);
  for (int d = 0; d < 3; ++d) hx(1, d) += u[d];
  Kokkos::deep_copy(p.x, hx);
  NeighborList<Exec> nl(0.1);
  nl.build(p, box);
  const NonAffine na = nonaffine_fluctuation(p, nl, box, box0, x0);
  ASSERT_EQ(na.contacts, 2.0);  // 0-1 through the face and 1-2
  // Both contacts: |Delta| = |u|, |eps l| = |e| |l_x| with the current separations
  // l_x = gap (1 + e) + u_x (pair 0-1) and gap (1 + e) - u_x (pair 1-2).
  const double un = std::sqrt(u[0] * u[0] + u[1] * u[1]);
  const double l01 = gap * (1 + e) + u[0], l12 = gap * (1 + e) - u[0];
  const double expect = 0.5 * (un / (std::fabs(e) * l01) + un / (std::fabs(e) * l12));
  EXPECT_NEAR(na.eta, expect, 1e-9 * expect);
  EXPECT_NEAR(na.eta_ratio, 2 * un / (std::fabs(e) * (l01 + l12)), 1e-9 * expect);
  // Normal parts along the current branch vectors l01 = (l01, u_y, 0) and l12 = (-l12, u_y, 0)
  // (from the other particle to particle 1; either order gives the same products):
  // Delta . n = u . l / |l|, (eps l) . n = e l_x^2 / |l|, both contacts compressed (e < 0).
  const double L01 = std::hypot(l01, u[1]), L12 = std::hypot(l12, u[1]);
  const double dn01 = (u[0] * l01 + u[1] * u[1]) / L01, dn12 = (-u[0] * l12 + u[1] * u[1]) / L12;
  const double en = std::fabs(e) * (l01 * l01 / L01 + l12 * l12 / L12);
  EXPECT_NEAR(na.eta_normal_ratio, (std::fabs(dn01) + std::fabs(dn12)) / en, 1e-9);
  // The signed mean: a non-affine move along +u_x opens contact 0-1 (undoing its affine
  // approach) and closes 1-2 further, so the two nearly cancel.
  EXPECT_NEAR(na.normal_relaxation, (dn01 + dn12) / en, 1e-9);
  EXPECT_GT(na.eta_normal_ratio, 10 * std::fabs(na.normal_relaxation));

  // Without the extra displacement the deformation is affine: no fluctuation at all.
  for (int d = 0; d < 3; ++d) hx(1, d) -= u[d];
  Kokkos::deep_copy(p.x, hx);
  const NonAffine affine = nonaffine_fluctuation(p, nl, box, box0, x0);
  EXPECT_LT(affine.eta, 1e-9);
  EXPECT_LT(affine.eta_normal_ratio, 1e-9);
  EXPECT_LT(std::fabs(affine.normal_relaxation), 1e-9);
  EXPECT_EQ(affine.contacts, 2.0);
}
