// The near list of the host one-pass kernel (NearRows in kernels/dem/contact_forces.hpp): the
// force passes that read only the owned entries within the near skin give the trajectory of
// the passes that read whole rows, bit for bit, for every host law path (frictionless contact
// by contact, frictional in batches and contact by contact, rolling springs), through
// neighbour rebuilds and through recordings forced by particles that move more than half the
// near skin; and a run cut into calls too short for the near list (which then reads whole
// rows) ends on the same bits. The near list's stream (kernels/cpu/near_stream.hpp) gives the
// bits of the near rows, batched frictional and frictionless contact by contact, signed
// zeros of rows without near entries included, for the linear and the restitution-damped
// Hertz-Mindlin laws, and leaves laws with several parameter sets to the rows; the frictional
// streams give the same bits from the particles' packed records as from their arrays.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/run/rng.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::bitwise_equal;

namespace {

using Frictionless = ContactModel<LinearNormal, NoTangential>;
using Frictional = ContactModel<LinearNormal, CoulombTangential>;
using Rolling = ContactModel<LinearNormal, CoulombTangential, RollingTorsion>;
using HertzFrictional = ContactModel<HertzRestitutionNormal, CoulombTangential>;
using HertzMindlin = ContactModel<HertzNormal, CoulombTangential>;
using Hysteretic = ContactModel<HystereticNormal, CoulombTangential>;

Frictionless make_model(Frictionless*) { return {LinearNormal::uniform(1e5, 1000), {}, {}}; }
Frictional make_model(Frictional*) {
  return {LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.5), {}};
}
// The studies' restitution-damped Hertz-Mindlin law, about as stiff as the linear one at these
// overlaps (sqrt(R* delta) ~ 0.05).
HertzFrictional make_model(HertzFrictional*) {
  return {HertzRestitutionNormal::uniform(2e6, 0.3),
          CoulombTangential::uniform(1.6e6, 0.4, 0.5, 0.5, CoulombTangential::MindlinRestitution),
          {}};
}
// The visco-elastic Hertz law in the Hertz moduli's stiffness form (length a_i + a_j, the
// Mindlin spring over the same length), sqrt(L delta) ~ 0.1 here.
HertzMindlin make_model(HertzMindlin*) {
  return {HertzNormal{PairTable<HertzNormal::Params>::uniform({1e6, 1e4, false})},
          CoulombTangential::uniform(8e5, 2e3, 0.5, 0.5, CoulombTangential::MindlinPairDiameter),
          {}};
}
// The cohesive studies' hysteretic law (k1/k2 = 0.666, k_c/k2 = 0.5) with the constant spring.
Hysteretic make_model(Hysteretic*) {
  return {HystereticNormal::uniform(0.666e5, 1e5, 0.5e5, 1000),
          CoulombTangential::uniform(8e4, 200, 0.5, 0.5),
          {}};
}
Rolling make_model(Rolling*) {
  return {LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.5),
          RollingTorsion::uniform({2e4, 50, 0.1, 2e4, 50, 0.1})};
}

template <class Exec, class V>
std::vector<double> host_copy(const V& v) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  return std::vector<double>(h.data(), h.data() + h.size());
}

// A loaded packing (compressed to phi ~ 0.64, then the strain stopped), stirred by random
// velocities large enough to move particles by more than the skin in the run below.
template <class Exec, class Model>
DemSystem<Exec, Model> stirred_packing(const DemParams& prm,
                                       const Model& model = make_model((Model*)nullptr)) {
  PeriodicBox box;
  GasSpec g;
  g.count = 2000, g.diameter_min = 1, g.diameter_max = 1.4, g.density = 2000, g.phi = 0.35;
  g.speed = 0.01, g.seed = 5;
  const HostParticles h = random_gas(g, box);
  DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
  sys.set_strain_rate(-3e-2, -3e-2, -3e-2);
  sys.step(1700);
  sys.set_strain_rate(0, 0, 0);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().v);
  for (int i = 0; i < sys.particles().n; ++i) {
    Stream s(77, i);
    for (int d = 0; d < 3; ++d) v(i, d) += s.uniform(-0.06, 0.06);
  }
  Kokkos::deep_copy(sys.particles().v, v);
  sys.refresh_forces();
  return sys;
}

template <class Exec, class Model>
void expect_same_bits(DemSystem<Exec, Model>& a, DemSystem<Exec, Model>& b, const char* what) {
  const auto& p = a.particles();
  const auto& q = b.particles();
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(p.x), host_copy<Exec>(q.x))) << what << ": x";
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(p.v), host_copy<Exec>(q.v))) << what << ": v";
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(p.f), host_copy<Exec>(q.f))) << what << ": f";
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(p.w), host_copy<Exec>(q.w))) << what << ": w";
  EXPECT_TRUE(bitwise_equal(host_copy<Exec>(p.torque), host_copy<Exec>(q.torque)))
      << what << ": torque";
  if (Model::history > 0) {
    EXPECT_TRUE(bitwise_equal(host_copy<Exec>(a.history_view()), host_copy<Exec>(b.history_view())))
        << what << ": springs";
  }
}

// The run parameters of the comparisons below.
DemParams stirred_params() {
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.1, prm.damping.translational = 20;
  prm.damping.rotational = 5;
  return prm;
}

template <class Exec, class Model>
void compare_with_whole_rows(bool batched) {
  DemParams prm = stirred_params();
  prm.batched_contacts = batched;
  DemParams whole = prm, fine = prm;
  prm.near_skin = 0.025;  // coarse: read more often than recorded in this stirred packing
  whole.near_skin = 0.0;  // no near list: every pass reads the whole rows
  fine.near_skin = -1.0;  // the default (a 16th or 32nd of the skin): recorded every few steps
  auto a = stirred_packing<Exec, Model>(prm);
  auto b = stirred_packing<Exec, Model>(whole);
  auto c = stirred_packing<Exec, Model>(fine);
  auto d = stirred_packing<Exec, Model>(prm);
  const long builds0 = a.neighbor_list().builds();
  const Measurements m0 = a.measure();
  for (int call = 0; call < 3; ++call) {
    a.step(200);
    b.step(200);
    c.step(200);
  }
  for (int s = 0; s < 600; ++s) d.step(1);  // calls too short for the near list
  ASSERT_GT(m0.contacts, a.particles().n) << "too few contacts for the comparison to bite";
  ASSERT_GT(a.neighbor_list().builds(), builds0 + 2) << "the run must cross rebuilds";
  ASSERT_NE(a.measure().contacts, m0.contacts) << "the contacts must change during the run";
  const NearListUse ua = a.near_list_use(), ub = b.near_list_use(), uc = c.near_list_use();
  const NearListUse ud = d.near_list_use();
  EXPECT_GT(ua.reads, 2 * ua.recordings) << "the coarse near skin is read more than recorded";
  EXPECT_GT(uc.recordings, a.neighbor_list().builds() - builds0 + 10)
      << "the default near skin must be recorded again between rebuilds";
  EXPECT_GT(uc.reads, 0) << "recordings " << uc.recordings;
  EXPECT_EQ(ub.reads, 0);
  EXPECT_EQ(ud.reads, 0);
  expect_same_bits(a, b, "coarse near skin against whole rows");
  expect_same_bits(c, b, "default near skin against whole rows");
  expect_same_bits(d, b, "single steps against whole rows");
}

// The stream against the near rows (stream off) and whole rows (no near list).
template <class Exec, class Model>
void compare_stream_with_rows(double near_skin) {
  DemParams prm = stirred_params();
  prm.near_skin = near_skin;
  DemParams rows = prm, whole = prm;
  rows.near_stream = false;
  // The default gap is a thirty-second of the skin where the frictional stream reads the
  // near list, a sixteenth for rows: the rows get the stream's gap, to be recorded and read
  // as often.
  if (near_skin < 0 && cpu_has_avx2() && Model::history > 0) rows.near_skin = prm.skin / 32;
  whole.near_skin = 0.0;
  auto a = stirred_packing<Exec, Model>(prm);
  auto b = stirred_packing<Exec, Model>(rows);
  auto c = stirred_packing<Exec, Model>(whole);
  const long builds0 = a.neighbor_list().builds();
  for (int call = 0; call < 3; ++call) {
    a.step(200);
    b.step(200);
    c.step(200);
  }
  ASSERT_GT(a.neighbor_list().builds(), builds0 + 2) << "the run must cross rebuilds";
  const NearListUse ua = a.near_list_use(), ub = b.near_list_use();
  EXPECT_EQ(ua.reads, ub.reads);
  EXPECT_EQ(ua.recordings, ub.recordings);
  EXPECT_EQ(ub.stream_reads, 0);
  if (cpu_has_avx2()) {
    EXPECT_EQ(ua.stream_reads, ua.reads) << "every read of the near list takes the stream";
  } else {
    EXPECT_EQ(ua.stream_reads, 0);
  }
  expect_same_bits(a, b, "stream against the near rows");
  expect_same_bits(a, c, "stream against whole rows");
}

// A law whose pair table holds a second parameter set reads the rows; the same law with one
// set reads the stream, and both give the same bits (species 1 is never used).
template <class Exec, class Model>
void several_parameter_sets_read_rows(const Model& two) {
  const DemParams prm = stirred_params();
  auto a = stirred_packing<Exec, Model>(prm, two);
  auto b = stirred_packing<Exec, Model>(prm);
  a.step(200);
  b.step(200);
  EXPECT_GT(a.near_list_use().reads, 0);
  EXPECT_EQ(a.near_list_use().stream_reads, 0) << "the stream broadcasts one parameter set";
  if (cpu_has_avx2()) {
    EXPECT_GT(b.near_list_use().stream_reads, 0);
  }
  expect_same_bits(a, b, "near rows against the stream");
}

// The frictional stream reading the particles' packed records (DemParams::packed_stream,
// here for any number of particles) against the stream reading the arrays: the same reads,
// the same bits, through rebuilds. With the default threshold a system this small reads the
// arrays.
template <class Exec, class Model>
void compare_packed_with_arrays() {
  DemParams prm = stirred_params(), arrays = stirred_params(), small = stirred_params();
  prm.packed_stream_min_particles = 0;
  arrays.packed_stream = false;
  auto a = stirred_packing<Exec, Model>(prm);
  auto b = stirred_packing<Exec, Model>(arrays);
  auto c = stirred_packing<Exec, Model>(small);
  ASSERT_LT(c.particles().n, small.packed_stream_min_particles);
  c.step(50);
  if (cpu_has_avx2()) {
    EXPECT_GT(c.near_list_use().stream_reads, 0);
  }
  EXPECT_EQ(c.near_list_use().packed_reads, 0) << "below the threshold the stream reads arrays";
  const long builds0 = a.neighbor_list().builds();
  for (int call = 0; call < 3; ++call) a.step(200), b.step(200);
  ASSERT_GT(a.neighbor_list().builds(), builds0 + 2) << "the run must cross rebuilds";
  const NearListUse ua = a.near_list_use(), ub = b.near_list_use();
  EXPECT_EQ(ua.stream_reads, ub.stream_reads);
  EXPECT_EQ(ub.packed_reads, 0);
  if (cpu_has_avx2()) {
    EXPECT_GT(ua.stream_reads, 100);
    EXPECT_EQ(ua.packed_reads, ua.stream_reads) << "every stream read takes the records";
  }
  expect_same_bits(a, b, "packed records against the arrays");
}

}  // namespace

template <class T>
class NearListTest : public ::testing::Test {};
TYPED_TEST_SUITE(NearListTest, granular::testing::ExecSpaces);

TYPED_TEST(NearListTest, FrictionlessRowsReadFromTheNearListGiveTheSameBits) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_with_whole_rows<TypeParam, Frictionless>(true);
}

TYPED_TEST(NearListTest, FrictionalBatchedAndScalarRowsFromTheNearListGiveTheSameBits) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_with_whole_rows<TypeParam, Frictional>(true);
  compare_with_whole_rows<TypeParam, Frictional>(false);
}

TYPED_TEST(NearListTest, RollingSpringRowsFromTheNearListGiveTheSameBits) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_with_whole_rows<TypeParam, Rolling>(true);
}

TYPED_TEST(NearListTest, FrictionalStreamOfTheNearListGivesTheBitsOfItsRows) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_stream_with_rows<TypeParam, Frictional>(0.025);  // coarse: read more than recorded
  compare_stream_with_rows<TypeParam, Frictional>(-1.0);   // the default: recorded every few steps
}

TYPED_TEST(NearListTest, FrictionalStreamFromPackedParticleRecordsGivesTheBitsOfTheArrays) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_packed_with_arrays<TypeParam, Frictional>();
}

// The Hertz law reads the masses too: from the velocity's quarter of the packed records.
TYPED_TEST(NearListTest, HertzStreamFromPackedParticleRecordsGivesTheBitsOfTheArrays) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_packed_with_arrays<TypeParam, HertzFrictional>();
}

TYPED_TEST(NearListTest, HertzBatchedAndScalarRowsFromTheNearListGiveTheSameBits) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_with_whole_rows<TypeParam, HertzFrictional>(true);
  compare_with_whole_rows<TypeParam, HertzFrictional>(false);
  compare_with_whole_rows<TypeParam, HertzMindlin>(true);
}

TYPED_TEST(NearListTest, HertzStreamOfTheNearListGivesTheBitsOfItsRows) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_stream_with_rows<TypeParam, HertzFrictional>(0.025);
  compare_stream_with_rows<TypeParam, HertzFrictional>(-1.0);
  compare_stream_with_rows<TypeParam, HertzMindlin>(0.025);
  compare_stream_with_rows<TypeParam, HertzMindlin>(-1.0);
}

// The hysteretic law's rows of four (delta_max, then the spring): batched and scalar rows, the
// stream, and the stream from the packed records.
TYPED_TEST(NearListTest, HystereticRowsStreamAndPackedRecordsFromTheNearListGiveTheSameBits) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_with_whole_rows<TypeParam, Hysteretic>(true);
  compare_with_whole_rows<TypeParam, Hysteretic>(false);
  compare_stream_with_rows<TypeParam, Hysteretic>(0.025);
  compare_stream_with_rows<TypeParam, Hysteretic>(-1.0);
  compare_packed_with_arrays<TypeParam, Hysteretic>();
}

TYPED_TEST(NearListTest, FrictionlessStreamOfTheNearListGivesTheBitsOfItsRows) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  compare_stream_with_rows<TypeParam, Frictionless>(0.025);
  compare_stream_with_rows<TypeParam, Frictionless>(-1.0);
}

TYPED_TEST(NearListTest, LawsWithSeveralParameterSetsReadTheNearRowsInsteadOfTheStream) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  Frictional two = make_model((Frictional*)nullptr);
  two.tangential.table.p[1][1].mu_s = 0.3;  // no particle has species 1: the same forces
  several_parameter_sets_read_rows<TypeParam>(two);
  Frictionless normal_two = make_model((Frictionless*)nullptr);
  normal_two.normal.table.p[0][1].gn = 900;
  normal_two.normal.table.p[1][0].gn = 900;
  several_parameter_sets_read_rows<TypeParam>(normal_two);
  HertzFrictional hertz_two = make_model((HertzFrictional*)nullptr);
  hertz_two.normal.table.p[1][1].alpha = 0.5;
  several_parameter_sets_read_rows<TypeParam>(hertz_two);
}

// A particle at rest with no partner: the integrator starts its force at -gamma_b * 0 = -0,
// and the rows add its empty sum, +0, which makes it +0. The stream must add it too.
template <class Exec, class Model>
void empty_row_adds_zero_sum() {
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0.0, box.len[d] = 12.0;
  HostParticles h;
  h.resize(3);
  const double at[3][3] = {{3, 3, 3}, {3.95, 3, 3}, {9, 9, 9}};  // a touching pair, one alone
  for (int i = 0; i < 3; ++i) {
    h.x[i] = at[i][0], h.y[i] = at[i][1], h.z[i] = at[i][2];
    h.radius[i] = 0.5, h.density[i] = 2000;
  }
  h.vx[0] = 0.01, h.vx[1] = -0.01, h.vy[1] = 0.002, h.wz[0] = 0.01;
  DemParams prm;
  prm.dt = 0.001, prm.skin = 0.1, prm.damping.translational = 20;  // the pair stays in contact
  prm.damping.rotational = 5;
  DemParams rows = prm;
  rows.near_stream = false;
  const Model model = make_model((Model*)nullptr);
  DemSystem<Exec, Model> a(Particles<Exec>::from_host(h), box, model, prm);
  DemSystem<Exec, Model> b(Particles<Exec>::from_host(h), box, model, rows);
  a.step(40);
  b.step(40);
  if (cpu_has_avx2()) {
    ASSERT_GT(a.near_list_use().stream_reads, 0);
  }
  ASSERT_EQ(a.measure().contacts, 1);
  const std::vector<double> v = host_copy<Exec>(a.particles().v);
  const std::vector<double> f = host_copy<Exec>(a.particles().f);
  const std::vector<double> q = host_copy<Exec>(a.particles().torque);
  int alone = -1;
  for (int i = 0; i < 3; ++i)
    if (v[3 * i] == 0.0 && v[3 * i + 1] == 0.0 && v[3 * i + 2] == 0.0) alone = i;
  ASSERT_GE(alone, 0);
  for (int d = 0; d < 3; ++d) {
    EXPECT_FALSE(std::signbit(f[3 * alone + d])) << "force " << d << " " << f[3 * alone + d];
    if (Model::rotations) {
      EXPECT_FALSE(std::signbit(q[3 * alone + d])) << "torque " << d << " " << q[3 * alone + d];
    }
  }
  expect_same_bits(a, b, "stream against the near rows");
}

TYPED_TEST(NearListTest, ARowWithoutNearEntriesAddsItsZeroSumInTheStreamAsInTheRows) {
  if constexpr (!forces_by_slabs<TypeParam>()) GTEST_SKIP() << "host one-pass kernel only";
  empty_row_adds_zero_sum<TypeParam, Frictional>();
  empty_row_adds_zero_sum<TypeParam, Frictionless>();
  empty_row_adds_zero_sum<TypeParam, HertzFrictional>();
}
