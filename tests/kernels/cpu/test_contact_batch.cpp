// Batched contact evaluation (kernels/cpu/contact_batch.hpp) against the scalar law: lane by
// lane on hand-made contacts that take every branch (sticking and sliding springs, an
// empty spring, a spring far out of the tangent plane, infinite friction at zero normal
// force, a tensile normal force, no tangential stiffness); and against the contact-by-
// contact rows of the host one-pass kernel: bitwise the same positions, velocities, spins,
// forces, torques and springs after a compression and a shear with rebuilds and two species
// of different stiffness and friction, and for a packing whose crowded particle owns more
// contacts than a batch holds (its row goes scalar); the same for the restitution-damped
// Hertz-Mindlin law, the visco-elastic Hertz law and the hysteretic law (each of its branches).
// Skipped where the processor has no AVX.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "kernels/contact/contact_model.hpp"
#include "kernels/cpu/contact_batch.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

using Friction = ContactModel<LinearNormal, CoulombTangential>;

// Species 0 and 1 with different normal stiffness, damping and friction (mixed pairs in
// between), so the batch's parameter gather is exercised.
LinearNormal two_species_normal() {
  LinearNormal n = LinearNormal::uniform(1e5, 1000);
  n.table.p[1][1] = {3e5, 1500};
  n.table.p[0][1] = n.table.p[1][0] = {1.5e5, 1200};
  return n;
}
Friction two_species_friction() {
  CoulombTangential t = CoulombTangential::uniform(8e4, 200, 0.5, 0.4);
  t.table.p[1][1] = {2.4e5, 300, 0.2, 0.2, CoulombTangential::Constant};
  t.table.p[0][1] = t.table.p[1][0] = {1.2e5, 250, 0.3, 0.25, CoulombTangential::Constant};
  return {two_species_normal(), t, {}};
}

using HertzFriction = ContactModel<HertzRestitutionNormal, CoulombTangential>;

// The restitution-damped Hertz-Mindlin law of the studies with two species, about as stiff as
// the linear set at these overlaps (sqrt(R* delta) ~ 0.05).
HertzFriction two_species_hertz() {
  constexpr int law = CoulombTangential::MindlinRestitution;
  HertzRestitutionNormal n = HertzRestitutionNormal::uniform(2e6, 0.3);
  n.table.p[1][1] = {3e6, 0.5};
  n.table.p[0][1] = n.table.p[1][0] = {2.5e6, 0.4};
  CoulombTangential t = CoulombTangential::uniform(1.6e6, 0.4, 0.5, 0.4, law);
  t.table.p[1][1] = {2.4e6, 0.6, 0.2, 0.2, law};
  t.table.p[0][1] = t.table.p[1][0] = {2e6, 0.5, 0.3, 0.25, law};
  return {n, t, {}};
}

using HertzMindlin = ContactModel<HertzNormal, CoulombTangential>;

// The visco-elastic Hertz law with two species in one form: the normal length R* (`reduced`,
// the mixtures' modulus form) or a_i + a_j (the stiffness form of the Hertz moduli), and the
// spring's law (constant, or Mindlin's over either length). The coefficients make it about as
// stiff as the linear set at these overlaps.
HertzMindlin two_species_hertz_mindlin(bool reduced, int law) {
  const double c = reduced ? 0.05 : 0.15;  // sqrt(L delta) at these overlaps
  const double t = law == CoulombTangential::Constant ? 1.0 : c;
  HertzNormal n{PairTable<HertzNormal::Params>::uniform({1e5 / c, 1000 / c, reduced})};
  n.table.p[1][1] = {1.5e5 / c, 1500 / c, reduced};
  n.table.p[0][1] = n.table.p[1][0] = {1.2e5 / c, 1200 / c, reduced};
  CoulombTangential s = CoulombTangential::uniform(8e4 / t, 200 / t, 0.5, 0.4, law);
  s.table.p[1][1] = {1.2e5 / t, 300 / t, 0.2, 0.2, law};
  s.table.p[0][1] = s.table.p[1][0] = {1e5 / t, 250 / t, 0.3, 0.25, law};
  return {n, s, {}};
}
using HystereticFriction = ContactModel<HystereticNormal, CoulombTangential>;

// The hysteretic law of the cohesive studies (k1/k2 = 0.666, k_c/k2 = 0.5) with two species and
// the constant Coulomb spring of two_species_friction.
HystereticFriction two_species_hysteretic() {
  HystereticNormal n = HystereticNormal::uniform(0.666e5, 1e5, 0.5e5, 1000);
  n.table.p[1][1] = {1.2e5, 1.5e5, 1e5, 1500};
  n.table.p[0][1] = n.table.p[1][0] = {0.9e5, 1.2e5, 0.2e5, 1200};
  return {n, two_species_friction().tangential, {}};
}

// The three forms the studies use.
const int kMindlinForms[3][2] = {{1, CoulombTangential::Constant},
                                 {0, CoulombTangential::MindlinPairDiameter},
                                 {1, CoulombTangential::MindlinReducedRadius}};

#if GRANULAR_CONTACT_BATCH
HostParticles two_species_gas(PeriodicBox& box, int count) {
  GasSpec g;
  g.count = count, g.diameter_min = 1, g.diameter_max = 1.6, g.density = 2000, g.phi = 0.35;
  g.speed = 0.01, g.seed = 11;
  HostParticles h = random_gas(g, box);
  for (int i = 0; i < h.size(); i += 3) h.species[i] = 1;
  return h;
}

template <class Exec, class V>
std::vector<double> host_copy(const V& v) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  return std::vector<double>(h.data(), h.data() + h.size());
}

using granular::testing::bitwise_equal;

template <class Exec, class Model>
void expect_bitwise_equal(const DemSystem<Exec, Model>& a, const DemSystem<Exec, Model>& b) {
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().x), host_copy<Exec>(b.particles().x)));
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().v), host_copy<Exec>(b.particles().v)));
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().f), host_copy<Exec>(b.particles().f)));
  if constexpr (Model::rotations) {
    EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().w), host_copy<Exec>(b.particles().w)));
    EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.particles().torque),
                              host_copy<Exec>(b.particles().torque)));
    EXPECT_TRUE(
        bitwise_equal(host_copy<Exec>(a.history_view()), host_copy<Exec>(b.history_view())));
  }
}

// Compresses the same gas twice, batched and contact by contact, and compares bitwise.
template <class Exec, class Model>
void compare_compression(const Model& model) {
  PeriodicBox box;
  const HostParticles h = two_species_gas(box, 2500);
  DemParams prm;
  prm.dt = 0.003, prm.skin = 0.1, prm.damping.translational = 100;
  prm.damping.rotational = 20;
  DemParams scalar = prm;
  scalar.batched_contacts = false;
  DemSystem<Exec, Model> a(Particles<Exec>::from_host(h), box, model, prm);
  DemSystem<Exec, Model> b(Particles<Exec>::from_host(h), box, model, scalar);
  a.set_strain_rate(-3e-2, -3e-2, -3e-2);  // to phi ~ 0.65: a loaded packing
  b.set_strain_rate(-3e-2, -3e-2, -3e-2);
  a.step(2200);
  b.step(2200);
  const Measurements m = a.measure();
  ASSERT_GT(m.contacts, a.particles().n) << "too few contacts for the comparison to bite";
  ASSERT_GT(a.neighbor_list().builds(), 2) << "the springs must survive rebuilds";
  expect_bitwise_equal(a, b);
  // Shearing the loaded packing makes contacts slide (the Coulomb branch of the lanes).
  a.set_strain_rate(2e-1, -2e-1, 0);
  b.set_strain_rate(2e-1, -2e-1, 0);
  a.step(400);
  b.step(400);
  expect_bitwise_equal(a, b);
}
#endif

}  // namespace

#if GRANULAR_CONTACT_BATCH  // (the batch exists only in GNU x86-64 host builds)
template <class T>
class ContactBatchTest : public ::testing::Test {};
TYPED_TEST_SUITE(ContactBatchTest, granular::testing::ExecSpaces);

TYPED_TEST(ContactBatchTest, BatchedFrictionalContactsGiveBitwiseTheContactByContactTrajectory) {
  using Exec = TypeParam;
  if constexpr (!forces_by_slabs<Exec>() || !ContactBatchLaw<Friction>::available) {
    GTEST_SKIP() << "no batched evaluation on this backend or compiler";
  } else {
    if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
    compare_compression<Exec>(two_species_friction());
  }
}

// The restitution-damped Hertz-Mindlin law in batches: parameters gathered for two species,
// then broadcast for one.
TYPED_TEST(ContactBatchTest, BatchedHertzContactsGiveBitwiseTheContactByContactTrajectory) {
  using Exec = TypeParam;
  if constexpr (!forces_by_slabs<Exec>() || !ContactBatchLaw<HertzFriction>::available) {
    GTEST_SKIP() << "no batched evaluation on this backend or compiler";
  } else {
    if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
    compare_compression<Exec>(two_species_hertz());
    HertzFriction one = two_species_hertz();
    one.normal = HertzRestitutionNormal::uniform(2e6, 0.3);
    one.tangential =
        CoulombTangential::uniform(1.6e6, 0.4, 0.5, 0.4, CoulombTangential::MindlinRestitution);
    ASSERT_TRUE(ContactBatchLaw<HertzFriction>::uniform(one));
    compare_compression<Exec>(one);
  }
}

// The visco-elastic Hertz law in its three forms (the mixtures', the Hertz moduli's and the
// reduced-radius Mindlin spring), parameters gathered for two species.
TYPED_TEST(ContactBatchTest, BatchedViscoElasticHertzContactsGiveBitwiseTheScalarTrajectory) {
  using Exec = TypeParam;
  if constexpr (!forces_by_slabs<Exec>() || !ContactBatchLaw<HertzMindlin>::available) {
    GTEST_SKIP() << "no batched evaluation on this backend or compiler";
  } else {
    if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
    for (const auto& f : kMindlinForms) {
      SCOPED_TRACE("reduced radius " + std::to_string(f[0]) + ", law " + std::to_string(f[1]));
      compare_compression<Exec>(two_species_hertz_mindlin(f[0] != 0, f[1]));
    }
  }
}

// The hysteretic law in batches (delta_max ahead of the spring in each history row):
// parameters gathered for two species, then broadcast for one.
TYPED_TEST(ContactBatchTest, BatchedHystereticContactsGiveBitwiseTheContactByContactTrajectory) {
  using Exec = TypeParam;
  if constexpr (!forces_by_slabs<Exec>() || !ContactBatchLaw<HystereticFriction>::available) {
    GTEST_SKIP() << "no batched evaluation on this backend or compiler";
  } else {
    if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
    compare_compression<Exec>(two_species_hysteretic());
    HystereticFriction one = two_species_hysteretic();
    one.normal = HystereticNormal::uniform(0.666e5, 1e5, 0.5e5, 1000);
    one.tangential = CoulombTangential::uniform(8e4, 200, 0.5, 0.4);
    ASSERT_TRUE(ContactBatchLaw<HystereticFriction>::uniform(one));
    compare_compression<Exec>(one);
  }
}

// One parameter set for every pair: the batch broadcasts it instead of gathering it.
TYPED_TEST(ContactBatchTest, BroadcastParametersOfOneSpeciesGiveBitwiseTheScalarTrajectory) {
  using Exec = TypeParam;
  if constexpr (!forces_by_slabs<Exec>() || !ContactBatchLaw<Friction>::available) {
    GTEST_SKIP() << "no batched evaluation on this backend or compiler";
  } else {
    if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
    const Friction one{
        LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.4), {}};
    ASSERT_TRUE(ContactBatchLaw<Friction>::uniform(one));
    ASSERT_FALSE(ContactBatchLaw<Friction>::uniform(two_species_friction()));
    Friction signed_zero = one;  // equal as numbers, not as bits: not broadcast
    for (auto& row : signed_zero.normal.table.p)
      for (auto& pair : row) pair.gn = 0.0;
    ASSERT_TRUE(ContactBatchLaw<Friction>::uniform(signed_zero));
    signed_zero.normal.table.p[1][1].gn = -0.0;
    EXPECT_FALSE(ContactBatchLaw<Friction>::uniform(signed_zero));
    compare_compression<Exec>(one);
  }
}

// A large sphere among small ones owns more neighbour entries than a batch holds: its row
// is evaluated contact by contact between batches, in its place in the order.
TYPED_TEST(ContactBatchTest, CrowdedRowBeyondTheBatchCapacityKeepsBitwiseTheSameForces) {
  using Exec = TypeParam;
  if constexpr (!forces_by_slabs<Exec>() || !ContactBatchLaw<Friction>::available) {
    GTEST_SKIP() << "no batched evaluation on this backend or compiler";
  } else {
    if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
    PeriodicBox box;
    const double L = 22.0, c = L / 2;
    for (int d = 0; d < 3; ++d) box.lo[d] = 0.0, box.len[d] = L;
    HostParticles h;
    std::vector<std::array<double, 4>> balls = {{c, c, c, 5.0}};  // identity 0: owns its row
    for (int a = 0; a < 22; ++a)
      for (int b = 0; b < 22; ++b)
        for (int k = 0; k < 22; k += 2) {
          const double x = a + 0.5, y = b + 0.5, z = k + 0.5 + 0.5 * (a % 2);
          const double d2 = (x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c);
          if (d2 < 5.45 * 5.45) continue;
          balls.push_back({x, y, z, 0.47 + 0.005 * (balls.size() % 5)});
        }
    h.resize(static_cast<int>(balls.size()));
    for (size_t i = 0; i < balls.size(); ++i) {
      h.x[i] = balls[i][0], h.y[i] = balls[i][1], h.z[i] = balls[i][2];
      h.radius[i] = balls[i][3], h.density[i] = 2000;
      h.vx[i] = 0.05 * std::sin(1.0 + i), h.vy[i] = 0.05 * std::cos(2.0 + i);
      h.vz[i] = 0.05 * std::sin(3.0 * i);
    }
    DemParams prm;
    prm.dt = 0.002, prm.skin = 0.3, prm.damping.translational = 10;
    DemParams scalar = prm;
    scalar.batched_contacts = false;
    const Friction model = two_species_friction();
    DemSystem<Exec, Friction> a(Particles<Exec>::from_host(h), box, model, prm);
    DemSystem<Exec, Friction> b(Particles<Exec>::from_host(h), box, model, scalar);
    a.set_strain_rate(-1e-2, -1e-2, -1e-2);
    b.set_strain_rate(-1e-2, -1e-2, -1e-2);
    a.step(1500);
    b.step(1500);
    // The crowded particle's row (wherever the sort put it) must exceed the batch.
    auto off =
        Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), a.neighbor_list().offsets());
    auto own =
        Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), a.neighbor_list().owned_end());
    int longest = 0;
    for (int i = 0; i < a.particles().n; ++i) longest = std::max(longest, own(i) - off(i));
    ASSERT_GT(longest, ContactBatch::kCap) << "no row beyond the batch: the fallback is untested";
    EXPECT_GT(a.measure().contacts, 200);
    expect_bitwise_equal(a, b);
  }
}

// Each lane of the batched law L against the scalar law, on 37 contacts that take every
// branch. `tweak(c, one, a, b)` changes pair (a, b)'s parameters of the scalar model `one`
// for contact c (the batch takes the same parameters).
// Laws with a history ahead of the spring (the hysteretic law's delta_max) start contacts on
// each of its branches in turn: virgin loading, the k2 branch, the adhesive branch, at
// delta_max; each must be taken.
template <class Model, class Tweak>
void expect_lanes_equal_scalar_law(const Model& model, Tweak tweak) {
  constexpr int H = Model::history;
  constexpr int O = batch_spring_at(ContactBatchLaw<Model>::law);  // the spring in the row
  static_assert(H == O + 3, "a spring of three after the normal law's history");
  const double dt = 0.003;
  ContactBatch cb;
  cb.form = ContactBatchLaw<Model>::form(model);
  std::vector<std::array<double, 13>> expected;
  int slid = 0, branches[3] = {0, 0, 0};
  for (int c = 0; c < 37; ++c) {  // not a multiple of the lane count: the padding is used
    const double u = 0.37 * c;
    Body bi{}, bj{};
    bi.a = 0.5 + 0.01 * c, bj.a = 0.7 - 0.005 * c;
    bi.s = c % 2, bj.s = (c / 2) % 2;
    bi.m = 1.0 + 0.03 * c, bj.m = 2.0 - 0.02 * c;
    // Centre distance just under contact: overlaps of 1-5 % of the radii.
    const double e[3] = {std::cos(u), std::sin(u), 0.5 * std::sin(2 * u)};
    const double len = (bi.a + bj.a) * (0.97 + 0.02 * std::sin(3 * u)) /
                       std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    const double rx = len * e[0], ry = len * e[1], rz = len * e[2];
    const double r2 = rx * rx + ry * ry + rz * rz;
    for (int d = 0; d < 3; ++d) {
      bi.v[d] = 0.3 * std::sin(u + d), bj.v[d] = -0.2 * std::cos(2 * u + d);
      bi.w[d] = 0.5 * std::cos(3 * u + d), bj.w[d] = 0.1 * std::sin(u - d);
    }
    const double rate[3] = {0.01, -0.02, 0.005};
    PairState s;
    pair_geometry(bi, bj, rx, ry, rz, r2, rate, true, s);
    // Springs: mostly small (sticking), some large (sliding), one empty, some far out of
    // the plane (the exact restoring factor instead of its series).
    std::array<double, 3> spring = {1e-4 * std::sin(5 * u), 1e-4 * std::cos(7 * u), 2e-5 * c};
    if (c % 5 == 1) spring = {0.3 * std::sin(u), -0.2, 0.1};
    if (c % 7 == 3) spring = {s.n[0] * 1e-3 + 1e-4, s.n[1] * 1e-3, s.n[2] * 1e-3};
    if (c == 4) spring = {0, 0, 0};
    std::array<double, H> h{};
    for (int d = 0; d < 3; ++d) h[O + d] = spring[d];
    if constexpr (O > 0)
      h[0] = (c % 4 == 0 ? 0.0 : c % 4 == 1 ? 1.2 : c % 4 == 2 ? 10.0 : 1.0) * s.delta;
    // The scalar law with this contact's parameters, and the batch with the same.
    Model one = model;
    tweak(c, one, bi.s, bj.s);
    cb.push(bi, bj, c, c, rx, ry, rz, rate, ContactBatchLaw<Model>::pair(one, bi.s, bj.s),
            h.data() + O);
    if constexpr (O > 0) cb.hd[c] = h[0];
    std::array<double, H> probe = h;
    double ft[3];
    const double fn = one.normal.force(s, probe.data());
    slid += one.tangential.force(s, fn, dt, probe.data() + O, ft);
    if constexpr (O > 0) {
      const HystereticNormal::Params& q = one.normal.table(bi.s, bj.s);
      double dm = h[0];
      const double elastic = HystereticNormal::piecewise(q, s.delta, dm);
      ++branches[elastic == q.k1 * s.delta ? 0 : elastic == -q.kc * s.delta ? 2 : 1];
    }
    PairForce out;
    one.evaluate(s, dt, h.data(), out);
    expected.push_back({out.f[0], out.f[1], out.f[2], out.q[0], out.q[1], out.q[2], out.qj[0],
                        out.qj[1], out.qj[2], h[O], h[O + 1], h[O + 2], O > 0 ? h[0] : 0.0});
  }
  cb.evaluate<ContactBatchLaw<Model>::law>(dt);
  ASSERT_GE(slid, 5) << "too few sliding lanes";
  ASSERT_LE(slid, cb.n - 10) << "too few sticking lanes";
  if constexpr (O > 0) {
    for (int b = 0; b < 3; ++b) EXPECT_GE(branches[b], 3) << "too few contacts on branch " << b;
  }
  for (int c = 0; c < cb.n; ++c) {
    const double got[13] = {cb.f0[c],
                            cb.f1[c],
                            cb.f2[c],
                            cb.q0[c],
                            cb.q1[c],
                            cb.q2[c],
                            cb.p0[c],
                            cb.p1[c],
                            cb.p2[c],
                            cb.h0[c],
                            cb.h1[c],
                            cb.h2[c],
                            O > 0 ? cb.hd[c] : 0.0};
    for (int e = 0; e < 13; ++e)
      EXPECT_EQ(std::memcmp(&got[e], &expected[c][e], sizeof(double)), 0)
          << "contact " << c << " value " << e << ": " << got[e] << " vs " << expected[c][e];
  }
}

TEST(ContactBatchLawTest, EveryLaneEqualsTheScalarLawBitwiseOnEachBranch) {
  if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
  const double inf = std::numeric_limits<double>::infinity();
  expect_lanes_equal_scalar_law(two_species_friction(), [&](int c, Friction& m, int a, int b) {
    CoulombTangential::Params& pt = m.tangential.table.p[a][b];
    LinearNormal::Params& pn = m.normal.table.p[a][b];
    if (c == 6) pt.kt = 0.0;                         // no tangential stiffness
    if (c == 8) pt.mu_s = pt.mu_d = inf;             // never slides
    if (c == 8 || c == 9) pn.kn = 0.0, pn.gn = 0.0;  // zero normal force
    if (c == 10) pn.kn = -1e3;                       // a tensile normal force
  });
}

// The restitution-damped Hertz-Mindlin law: reduced radius and mass per lane, the dashpots'
// square roots, and the spring that keeps no dashpot share after a slip.
TEST(ContactBatchLawTest, EveryHertzLaneEqualsTheScalarLawBitwiseOnEachBranch) {
  if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
  const double inf = std::numeric_limits<double>::infinity();
  expect_lanes_equal_scalar_law(two_species_hertz(), [&](int c, HertzFriction& m, int a, int b) {
    CoulombTangential::Params& pt = m.tangential.table.p[a][b];
    HertzRestitutionNormal::Params& pn = m.normal.table.p[a][b];
    if (c == 6) pt.kt = 0.0;                   // no tangential stiffness
    if (c == 8) pt.mu_s = pt.mu_d = inf;       // never slides
    if (c == 8 || c == 9) pn.K = 0.0;          // zero normal force
    if (c == 10 || c == 12) pn.alpha = 40.0;   // the dashpot outweighs the spring
    if (c == 11) pt.gt = 0.0, pn.alpha = 0.0;  // no damping
  });
}

// The hysteretic law: delta_max per lane, each branch of the piecewise force (the adhesive one
// moves delta_max), with the constant Coulomb spring.
TEST(ContactBatchLawTest, EveryHystereticLaneEqualsTheScalarLawBitwiseOnEachBranch) {
  if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
  const double inf = std::numeric_limits<double>::infinity();
  expect_lanes_equal_scalar_law(two_species_hysteretic(),
                                [&](int c, HystereticFriction& m, int a, int b) {
                                  CoulombTangential::Params& pt = m.tangential.table.p[a][b];
                                  HystereticNormal::Params& pn = m.normal.table.p[a][b];
                                  if (c == 6) pt.kt = 0.0;              // no tangential stiffness
                                  if (c == 8) pt.mu_s = pt.mu_d = inf;  // never slides
                                  if (c == 10 || c == 14)
                                    pn.kc = 0.0;  // no adhesion: the branch gives zero force
                                  if (c == 11) pt.gt = 0.0, pn.gn = 0.0;  // no damping
                                  if (c == 13) pn.k1 = pn.k2;             // no plastic overlap
                                });
}

// The visco-elastic Hertz law in each form: the normal length, the spring's scale (none for
// the constant spring), the dashpots proportional to sqrt(L delta).
TEST(ContactBatchLawTest, EveryViscoElasticHertzLaneEqualsTheScalarLawBitwiseOnEachBranch) {
  if (!cpu_has_avx()) GTEST_SKIP() << "the processor has no AVX";
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& f : kMindlinForms) {
    SCOPED_TRACE("reduced radius " + std::to_string(f[0]) + ", law " + std::to_string(f[1]));
    const HertzMindlin model = two_species_hertz_mindlin(f[0] != 0, f[1]);
    ASSERT_TRUE(ContactBatchLaw<HertzMindlin>::usable(model));
    expect_lanes_equal_scalar_law(model, [&](int c, HertzMindlin& m, int a, int b) {
      CoulombTangential::Params& pt = m.tangential.table.p[a][b];
      HertzNormal::Params& pn = m.normal.table.p[a][b];
      if (c == 6) pt.kt = 0.0;                       // no tangential stiffness
      if (c == 8) pt.mu_s = pt.mu_d = inf;           // never slides
      if (c == 8 || c == 9) pn.K = 0.0, pn.G = 0.0;  // zero normal force
      if (c == 10) pn.K = -1e3;                      // a tensile normal force
    });
  }
}
#endif

TEST(ContactBatchLawTest, EachBatchedLawTakesOnlyItsOwnFormsOfTheSpring) {
  Friction m = two_species_friction();
  EXPECT_TRUE(ContactBatchLaw<Friction>::usable(m));
  m.tangential.table.p[0][1].law = CoulombTangential::MindlinPairDiameter;
  EXPECT_FALSE(ContactBatchLaw<Friction>::usable(m));
  // The visco-elastic Hertz law: one form for every pair.
  HertzMindlin v = two_species_hertz_mindlin(false, CoulombTangential::MindlinPairDiameter);
  EXPECT_TRUE(ContactBatchLaw<HertzMindlin>::usable(v));
  v.tangential.table.p[0][1].law = CoulombTangential::MindlinReducedRadius;
  EXPECT_FALSE(ContactBatchLaw<HertzMindlin>::usable(v)) << "two spring forms";
  v = two_species_hertz_mindlin(false, CoulombTangential::MindlinPairDiameter);
  v.normal.table.p[1][1].reduced_radius = true;
  EXPECT_FALSE(ContactBatchLaw<HertzMindlin>::usable(v)) << "two normal lengths";
  v = two_species_hertz_mindlin(true, CoulombTangential::MindlinRestitution);
  EXPECT_FALSE(ContactBatchLaw<HertzMindlin>::usable(v)) << "that spring is HertzRestitution's";
  // The Hertz law is batched with its own spring, the restitution-damped Mindlin one.
  HertzFriction h = two_species_hertz();
  EXPECT_TRUE(ContactBatchLaw<HertzFriction>::usable(h));
  EXPECT_FALSE(ContactBatchLaw<HertzFriction>::uniform(h));
  h.tangential.table.p[1][0].law = CoulombTangential::MindlinReducedRadius;
  EXPECT_FALSE(ContactBatchLaw<HertzFriction>::usable(h));
  h = two_species_hertz();
  h.coulomb_elastic_normal = true;
  EXPECT_FALSE(ContactBatchLaw<HertzFriction>::usable(h))
      << "the batch limits with the total force";
  // The hysteretic law: the constant spring, the limit with the total force.
  HystereticFriction y = two_species_hysteretic();
  EXPECT_TRUE(ContactBatchLaw<HystereticFriction>::usable(y));
  EXPECT_FALSE(ContactBatchLaw<HystereticFriction>::uniform(y));
  y.tangential.table.p[0][0].law = CoulombTangential::MindlinPairDiameter;
  EXPECT_FALSE(ContactBatchLaw<HystereticFriction>::usable(y));
  y = two_species_hysteretic();
  y.coulomb_elastic_normal = true;
  EXPECT_FALSE(ContactBatchLaw<HystereticFriction>::usable(y));
  EXPECT_FALSE((ContactBatchLaw<ContactModel<LinearNormal>>::available))
      << "the frictionless law measured slower batched";
}
