// Particle arrays change hands without copies left behind: a moved-from Particles holds no
// array (Kokkos 3.4's View copies when moved, so this needs Particles' own move), and a system
// made from std::move(particles) holds the only reference to its arrays, so the first sort's
// permuted copies do not sit beside the caller's originals at the peak of memory.
#include <gtest/gtest.h>

#include <utility>

#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/packing.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

template <class T>
class ParticleArraysTest : public ::testing::Test {};
TYPED_TEST_SUITE(ParticleArraysTest, granular::testing::ExecSpaces);

TYPED_TEST(ParticleArraysTest, MoveHandsOverEveryArrayAndLeavesTheSourceEmpty) {
  using Exec = TypeParam;
  Particles<Exec> a(100);
  const double* x = a.x.data();
  Particles<Exec> b(std::move(a));
  EXPECT_EQ(b.x.data(), x);
  EXPECT_EQ(b.n, 100);
  EXPECT_EQ(b.x.use_count(), 1);
  EXPECT_EQ(b.torque.use_count(), 1);
  EXPECT_EQ(b.id.use_count(), 1);
  EXPECT_EQ(a.n, 0);
  EXPECT_EQ(a.x.data(), nullptr);
  EXPECT_EQ(a.radius.data(), nullptr);
  EXPECT_EQ(a.species.data(), nullptr);
  Particles<Exec> c;
  c = std::move(b);
  EXPECT_EQ(c.x.data(), x);
  EXPECT_EQ(c.x.use_count(), 1);
  EXPECT_EQ(b.x.data(), nullptr);
}

TYPED_TEST(ParticleArraysTest, SystemMadeFromMovedParticlesReleasesTheCallersArrays) {
  using Exec = TypeParam;
  GasSpec g;
  g.count = 500, g.diameter_min = 1, g.diameter_max = 2, g.density = 2000, g.phi = 0.3;
  g.seed = 3;
  PeriodicBox box;
  auto p = Particles<Exec>::from_host(random_gas(g, box));
  const auto original_x = p.x;  // watches the caller's array
  ASSERT_EQ(original_x.use_count(), 2);
  DemParams prm;
  prm.dt = 0.004, prm.skin = 0.1;
  using Model = ContactModel<LinearNormal, NoTangential>;
  const Model model{LinearNormal::uniform(1e5, 1000), {}, {}};
  DemSystem<Exec, Model> sys(std::move(p), box, model, prm);
  EXPECT_EQ(p.x.data(), nullptr);
  // The sort at the first build replaced the system's arrays: nothing but the watcher holds
  // the original any more, and the system's own arrays have one owner each.
  EXPECT_EQ(original_x.use_count(), 1);
  EXPECT_NE(sys.particles().x.data(), original_x.data());
  EXPECT_EQ(sys.particles().x.use_count(), 1);
  EXPECT_EQ(sys.particles().v.use_count(), 1);
}
