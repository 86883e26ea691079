// The mixed-precision force pass (DemParams::mixed_precision, kernels/dem/fixed_point.hpp):
// fixed-point separations are the minimum image to within one integer step; the forces of a
// dense frictional packing agree with the double pass to within the error that one step of
// separation can make; a damped compression through a shrinking box (whose step changes every
// step) follows the double trajectory to round-off levels; and the settings it cannot serve are
// refused with a message.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/run/rng.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "kernels/dem/fixed_point.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

namespace {

using Frictional = ContactModel<LinearNormal, CoulombTangential>;
constexpr double kN = 1e5, kGammaN = 1000, kGammaT = 200;

Frictional frictional() {
  return {
      LinearNormal::uniform(kN, kGammaN), CoulombTangential::uniform(8e4, kGammaT, 0.5, 0.4), {}};
}

// A gas at phi 0.4 squeezed affinely to phi 0.62: a dense packing with overlaps of a few
// percent of a radius, made without running the engine.
HostParticles squeezed_gas(PeriodicBox& box, int count) {
  GasSpec g;
  g.count = count, g.diameter_min = 1, g.diameter_max = 1.4, g.density = 2000, g.phi = 0.4;
  g.speed = 0.01, g.seed = 11;
  HostParticles h = random_gas(g, box);
  const double c = std::cbrt(0.4 / 0.62);
  for (int i = 0; i < h.size(); ++i) h.x[i] *= c, h.y[i] *= c, h.z[i] *= c;
  for (int d = 0; d < 3; ++d) box.lo[d] *= c, box.len[d] *= c;
  return h;
}

DemParams params(bool mixed) {
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.1, prm.damping.translational = 100;
  prm.damping.rotational = 20;
  prm.two_pass_forces = true;  // the double reference runs the same kernel
  prm.mixed_precision = mixed;
  return prm;
}

// An (n x 3) array of the system's particles, row by particle identity: each system sorts its
// arrays by cell at every rebuild, so two runs apart by a rounding need not share an order.
template <class System, class V>
std::vector<double> by_identity(const System& sys, const V& v) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().id);
  std::vector<double> out(3 * h.extent(0));
  for (size_t i = 0; i < h.extent(0); ++i)
    for (int d = 0; d < 3; ++d) out[3 * id(i) + d] = h(i, d);
  return out;
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0;
  for (size_t k = 0; k < a.size(); ++k) m = std::max(m, std::fabs(a[k] - b[k]));
  return m;
}

}  // namespace

TEST(MixedPrecision, FixedPointSeparationIsTheMinimumImageWithinOneStep) {
  PeriodicBox box;
  const double lo[3] = {-2.0, 5.0, 0.3}, len[3] = {30.0, 17.3, 45.0};
  double step[3], per[3];
  for (int d = 0; d < 3; ++d) {
    box.lo[d] = lo[d], box.len[d] = len[d];
    step[d] = len[d] / kFixedPointSteps, per[d] = kFixedPointSteps / len[d];
  }
  double worst = 0;  // largest error in steps
  Stream rng(3, 0);
  for (int k = 0; k < 200000; ++k) {
    const int d = k % 3;
    // Positions up to a tenth of the box outside it (walls, positions before their wrap).
    const double xi = lo[d] + rng.uniform(-0.1, 1.1) * len[d];
    const double xj = lo[d] + rng.uniform(-0.1, 1.1) * len[d];
    const double exact = box.min_image(box.min_image(xi - xj, d), d);
    if (std::fabs(std::fabs(exact) - 0.5 * len[d]) < 1e-3) continue;  // image ambiguous
    const double fixed = fixed_point_separation(to_fixed_point(xi, lo[d], per[d]),
                                                to_fixed_point(xj, lo[d], per[d]), step[d]);
    worst = std::max(worst, std::fabs(fixed - exact) / step[d]);
  }
  // Each position is rounded to the nearest step (half a step at most), so the separation is
  // within one step; two hundred thousand pairs come close to that bound.
  EXPECT_LE(worst, 1.0 + 1e-5);
  EXPECT_GT(worst, 0.9);
}

template <class T>
class MixedPrecisionTest : public ::testing::Test {};
TYPED_TEST_SUITE(MixedPrecisionTest, granular::testing::ExecSpaces);

TYPED_TEST(MixedPrecisionTest, ForcesAgreeWithDoubleWithinWhatOneStepOfSeparationCanMove) {
  using Exec = TypeParam;
  PeriodicBox box;
  const HostParticles h = squeezed_gas(box, 2000);
  DemSystem<Exec, Frictional> ref(Particles<Exec>::from_host(h), box, frictional(), params(false));
  DemSystem<Exec, Frictional> mix(Particles<Exec>::from_host(h), box, frictional(), params(true));
  const Measurements m = ref.measure();
  ASSERT_GT(m.z, 4.0) << "not a dense packing";
  const std::vector<double> f0 = by_identity(ref, ref.particles().f);
  const std::vector<double> f1 = by_identity(mix, mix.particles().f);
  const std::vector<double> v = by_identity(ref, ref.particles().v);
  double f_max = 0, v_max = 0;
  for (double x : f0) f_max = std::max(f_max, std::fabs(x));
  for (double x : v) v_max = std::max(v_max, std::fabs(x));
  // A separation error e (|e| <= sqrt(3) steps) moves a contact's spring force by k e and
  // turns its normal by at most 2 e / r (r >= 2 a_min - delta_max > 0.9): the elastic force
  // k delta by k delta 2 e / r, the dashpots (g |v_rel| <= 2 sqrt(3) g v_max) by as much
  // again. A particle has at most 16 contacts here.
  const double steps = std::sqrt(3.0) * box.len[0] / kFixedPointSteps;
  const double r_min = 0.9, delta_max = m.max_overlap * 0.5;
  const double per_contact = steps * (kN * (1 + 2 * delta_max / r_min) +
                                      2 * std::sqrt(3.0) * (kGammaN + kGammaT) * v_max * 2 / r_min);
  const double diff = max_abs_diff(f0, f1);
  EXPECT_LE(diff, 16 * per_contact) << "forces up to " << f_max;
  EXPECT_GT(diff, 0.0) << "the mixed pass gave the double forces: did it read the integers?";
  EXPECT_LT(diff, 1e-6 * f_max);
}

TYPED_TEST(MixedPrecisionTest, DampedCompressionFollowsTheDoubleTrajectory) {
  using Exec = TypeParam;
  PeriodicBox box;
  GasSpec g;
  g.count = 800, g.diameter_min = 1, g.diameter_max = 1.4, g.density = 2000, g.phi = 0.42;
  g.speed = 0.01, g.seed = 4;
  const HostParticles h = random_gas(g, box);
  Measurements end[2];
  std::vector<double> x[2];
  for (int k = 0; k < 2; ++k) {
    DemSystem<Exec, Frictional> sys(Particles<Exec>::from_host(h), box, frictional(),
                                    params(k == 1));
    // The box shrinks by 1.2 % of its length per 100 steps (phi 0.42 to 0.62): a mixed pass
    // that kept the integer step of the first box would misplace contacts by ~0.1 diameter.
    sys.set_strain_rate(-3e-2, -3e-2, -3e-2);
    sys.step(1000);
    end[k] = sys.measure();
    x[k] = by_identity(sys, sys.particles().x);
  }
  ASSERT_GT(end[0].contacts, 400) << "no contacts were compared";
  // Measured: positions 1.8e-8 apart (seven integer steps of this 12-long box), pressure
  // 1e-9 and kinetic energy 1e-8 relative; the bounds are fifty to a thousand times those,
  // and far below what a wrong separation moves (a tenth of a diameter, or the whole force).
  EXPECT_LT(max_abs_diff(x[0], x[1]), 1e-6);
  EXPECT_LT(std::fabs(end[1].pressure - end[0].pressure), 1e-6 * end[0].pressure);
  EXPECT_LT(std::fabs(end[1].ekin - end[0].ekin), 1e-5 * end[0].ekin);
}

TEST(MixedPrecision, IsRefusedWithAMultiContactLaw) {
  using Exec = Kokkos::DefaultExecutionSpace;
  using Model = ContactModel<HertzNormal, NoTangential>;
  PeriodicBox box;
  const HostParticles h = squeezed_gas(box, 300);
  const Model model{
      {PairTable<HertzNormal::Params>::uniform(HertzNormal::stiffness_form(29e3, 0.2, 1000))},
      {},
      {}};
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, params(true));
  MultiContact mc;
  mc.mode = MultiContact::Stress;
  try {
    sys.set_multicontact(mc);
    FAIL() << "a multi-contact law ran with mixed precision";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mixed precision"), std::string::npos) << e.what();
  }
}

TEST(MixedPrecision, IsRefusedInABoxShorterThanTwiceTheNeighbourReach) {
  using Exec = Kokkos::DefaultExecutionSpace;
  HostParticles h;
  h.resize(2);
  h.x = {1.0, 2.0}, h.y = {1.0, 1.0}, h.z = {1.0, 1.0};
  h.radius = {0.5, 0.5}, h.density = {2000, 2000};
  PeriodicBox box;
  box.len[0] = 10, box.len[1] = 10, box.len[2] = 2.0;  // reach 2 a + skin = 1.1
  box.periodic[2] = false;
  try {
    DemSystem<Exec, Frictional> sys(Particles<Exec>::from_host(h), box, frictional(), params(true));
    FAIL() << "a box 2 long in z ran with mixed precision";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("dimension 2"), std::string::npos) << what;
    EXPECT_NE(what.find("mixed_precision"), std::string::npos) << what;
  }
}
