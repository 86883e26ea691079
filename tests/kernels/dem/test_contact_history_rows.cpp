// Contact history kept in the owners' rows only (ContactHistory with OwnerRows,
// NeighborList::pair_begin): after a compression and a shear with rebuilds and particle
// reordering, every touching contact's spring sits in the row of its owned entry (it lies in
// that contact's tangent plane, as the law keeps it) and every apart pair's row is empty;
// the rows are exactly half the list. A restart written with one history row per list
// entry (the earlier layout) loads into the owner rows bitwise. A system on the two-pass
// kernel (per-contact rows, the list's pair index remade on loading) continues bitwise from
// its restart.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <utility>

#include "core/io/output.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/restart_file.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {

using Friction = ContactModel<LinearNormal, CoulombTangential>;

template <class Exec>
DemSystem<Exec, Friction> sheared_packing(bool two_pass = false) {
  GasSpec g;
  g.count = 1200, g.diameter_min = 1, g.diameter_max = 2, g.density = 2000, g.phi = 0.35;
  g.speed = 0.01, g.seed = 5;
  PeriodicBox box;
  const HostParticles h = random_gas(g, box);
  DemParams prm;
  prm.dt = 0.003, prm.skin = 0.1, prm.damping.translational = 100;
  prm.damping.rotational = 20;
  prm.two_pass_forces = two_pass;
  const Friction model{
      LinearNormal::uniform(1e5, 1000), CoulombTangential::uniform(8e4, 200, 0.5, 0.5), {}};
  DemSystem<Exec, Friction> sys(Particles<Exec>::from_host(h), box, model, prm);
  sys.set_strain_rate(-3e-2, -3e-2, -3e-2);  // to phi ~ 0.63: a loaded packing
  sys.step(2000);
  sys.set_strain_rate(1e-1, -1e-1, 0);  // shear: springs load, some slide
  sys.step(300);
  return sys;
}

template <class V>
auto on_host(const V& v) {
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
}

}  // namespace

template <class T>
class ContactHistoryRowsTest : public ::testing::Test {};
TYPED_TEST_SUITE(ContactHistoryRowsTest, granular::testing::ExecSpaces);

TYPED_TEST(ContactHistoryRowsTest, EachContactsSpringSitsInItsOwnersRowThroughRebuilds) {
  using Exec = TypeParam;
  auto sys = sheared_packing<Exec>();
  const auto& nl = sys.neighbor_list();
  ASSERT_GT(nl.builds(), 3) << "the springs must survive rebuilds and reordering";
  ASSERT_EQ(2 * nl.num_pairs(), nl.num_entries()) << "the list holds each pair twice";
  const auto hist = on_host(sys.history_view());
  ASSERT_EQ(static_cast<int>(hist.extent(0)), nl.num_pairs());
  const auto off = on_host(nl.offsets()), own = on_host(nl.owned_end());
  const auto pb = on_host(nl.pair_begin()), nb = on_host(nl.neighbors());
  const auto x = on_host(sys.particles().x);
  const auto a = on_host(sys.particles().radius);
  const PeriodicBox box = sys.box();
  int touching = 0, loaded = 0;
  for (int i = 0; i < sys.particles().n; ++i) {
    ASSERT_EQ(pb(i + 1) - pb(i), own(i) - off(i));
    for (int k = off(i); k < own(i); ++k) {
      const int j = nb(k), r = pb(i) + (k - off(i));
      double n[3], d2 = 0;
      for (int c = 0; c < 3; ++c) n[c] = box.min_image(x(i, c) - x(j, c), c), d2 += n[c] * n[c];
      const double s2 = hist(r, 0) * hist(r, 0) + hist(r, 1) * hist(r, 1) + hist(r, 2) * hist(r, 2);
      const double gap = std::sqrt(d2) - a(i) - a(j);
      // Positions moved by one drift since the forces were evaluated: decide on clear cases.
      if (gap > 1e-6) {
        EXPECT_EQ(s2, 0.0) << "apart pair " << i << "-" << j << " keeps a spring";
      } else if (gap < -1e-6) {
        ++touching;
        if (s2 == 0.0) continue;
        ++loaded;
        const double dn =
            (hist(r, 0) * n[0] + hist(r, 1) * n[1] + hist(r, 2) * n[2]) / std::sqrt(d2);
        // Rotated into the tangent plane at the last evaluation; the normal has turned by
        // at most one step's rotation since.
        EXPECT_LT(std::abs(dn), 1e-3 * std::sqrt(s2))
            << "spring of " << i << "-" << j << " is not in its tangent plane";
      }
    }
  }
  EXPECT_GT(touching, sys.particles().n) << "too few contacts for the check to bite";
  EXPECT_GT(loaded, touching / 2) << "the shear must load most springs";
}

TYPED_TEST(ContactHistoryRowsTest, RestartWithOneRowPerListEntryLoadsIntoOwnerRowsBitwise) {
  using Exec = TypeParam;
  auto sys = sheared_packing<Exec>();
  const auto& nl = sys.neighbor_list();
  const auto hist = on_host(sys.history_view());
  const auto off = on_host(nl.offsets()), own = on_host(nl.owned_end());
  const auto pb = on_host(nl.pair_begin()), nb = on_host(nl.neighbors());
  const auto id = on_host(sys.particles().id);
  const int n = sys.particles().n, entries = nl.num_entries();
  // The earlier layout: row k for list entry k (the owner's entries hold the springs, the
  // other side's rows zero), partner identities per entry, the list's offsets.
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> values("values", entries, 3);
  Kokkos::View<int*, Kokkos::HostSpace> ids("ids", entries);
  for (int i = 0; i < n; ++i)
    for (int k = off(i); k < off(i + 1); ++k) {
      ids(k) = id(nb(k));
      if (k < own(i))
        for (int c = 0; c < 3; ++c) values(k, c) = hist(pb(i) + (k - off(i)), c);
    }
  const auto dir = granular::testing::unique_temp_path("granular_history_rows");
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "old.h5").string();
  {
    H5Writer w(path);
    save_view(w, "/h/values", values);
    save_view(w, "/h/partner_ids", ids);
    save_view(w, "/h/offsets", off);
    w.commit();
  }
  ContactHistory<Exec, 3, true> loaded;
  load_history(H5Reader(path), "/h", loaded, nl);
  const auto got = on_host(loaded.values());
  ASSERT_EQ(got.extent(0), hist.extent(0));
  EXPECT_EQ(std::memcmp(got.data(), hist.data(), hist.size() * sizeof(double)), 0);
  // A file whose rows match neither layout is refused by name.
  {
    H5Writer w(path);
    save_view(w, "/h/values", Kokkos::subview(values, std::make_pair(0, 3), Kokkos::ALL));
    save_view(w, "/h/partner_ids", Kokkos::subview(ids, std::make_pair(0, 3)));
    save_view(w, "/h/offsets", off);
    w.commit();
  }
  ContactHistory<Exec, 3, true> bad;
  EXPECT_THROW(load_history(H5Reader(path), "/h", bad, nl), InputError);
  std::filesystem::remove_all(dir);
}

// A system made from a restart group alone (no fresh system, neighbour build or force pass
// first) continues the saved one bitwise, on the one-pass and the two-pass force kernels: the
// sheared packing's strain rate, clock, list, springs and forces all come from the file.
TYPED_TEST(ContactHistoryRowsTest, SystemMadeFromItsRestartAloneContinuesBitwise) {
  using Exec = TypeParam;
  using System = DemSystem<Exec, Friction>;
  for (const bool two_pass : {false, true}) {
    auto a = sheared_packing<Exec>(two_pass);
    const auto dir = granular::testing::unique_temp_path("granular_restart_alone");
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "restart.h5").string();
    {
      H5Writer w(path);
      write_restart(w, "/r", a);
      w.commit();
    }
    System b(read_restart<System>(H5Reader(path), "/r"), a.model(), a.params(), "restart group /r");
    EXPECT_EQ(b.neighbor_list().builds(), a.neighbor_list().builds());
    EXPECT_EQ(b.steps(), a.steps());
    EXPECT_EQ(b.time(), a.time());
    a.step(400);
    b.step(400);
    const auto xa = on_host(a.particles().x), xb = on_host(b.particles().x);
    const auto fa = on_host(a.particles().f), fb = on_host(b.particles().f);
    const auto ha = on_host(a.history_view()), hb = on_host(b.history_view());
    EXPECT_EQ(std::memcmp(xa.data(), xb.data(), xa.size() * sizeof(double)), 0) << two_pass;
    EXPECT_EQ(std::memcmp(fa.data(), fb.data(), fa.size() * sizeof(double)), 0) << two_pass;
    ASSERT_EQ(ha.size(), hb.size());
    EXPECT_EQ(std::memcmp(ha.data(), hb.data(), ha.size() * sizeof(double)), 0) << two_pass;
    std::filesystem::remove_all(dir);
  }
}

TYPED_TEST(ContactHistoryRowsTest, TwoPassSystemContinuesBitwiseFromItsRestart) {
  using Exec = TypeParam;
  auto a = sheared_packing<Exec>(true);
  const auto dir = granular::testing::unique_temp_path("granular_two_pass_restart");
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "restart.h5").string();
  {
    H5Writer w(path);
    write_restart(w, "/r", a);
    w.commit();
  }
  // A system moved on by a few steps: everything the next step reads must come from the file.
  auto b = sheared_packing<Exec>(true);
  b.step(7);
  load_restart(H5Reader(path), "/r", b);
  const long builds = a.neighbor_list().builds();
  a.step(400);
  b.step(400);
  ASSERT_GT(a.neighbor_list().builds(), builds) << "the continuation must rebuild the list";
  const auto xa = on_host(a.particles().x), xb = on_host(b.particles().x);
  const auto fa = on_host(a.particles().f), fb = on_host(b.particles().f);
  EXPECT_EQ(std::memcmp(xa.data(), xb.data(), xa.size() * sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(fa.data(), fb.data(), fa.size() * sizeof(double)), 0);
  std::filesystem::remove_all(dir);
}

// A saved state whose particle arrays disagree in length (a damaged or foreign restart) is
// refused by restore(), naming its origin, before any array of the system is replaced.
TYPED_TEST(ContactHistoryRowsTest, SavedStateWithArraysOfDifferentLengthsIsRefused) {
  using Exec = TypeParam;
  auto a = sheared_packing<Exec>();
  auto s = a.saved();
  using vec_view = typename Particles<Exec>::vec_view;
  s.particles.v = vec_view("short_v", s.particles.n - 1);
  const double* const x_before = a.particles().x.data();
  const double* const v_before = a.particles().v.data();
  try {
    a.restore(s, "restart group /test");
    ADD_FAILURE() << "a state with a short velocity array was restored";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("restart group /test"), std::string::npos) << e.what();
  }
  EXPECT_EQ(a.particles().x.data(), x_before);  // the system kept its own arrays
  EXPECT_EQ(a.particles().v.data(), v_before);
}
