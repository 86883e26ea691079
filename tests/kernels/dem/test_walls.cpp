// Walls and mixed boundaries: a sphere on a rigid wall against the closed forms of Hertz
// and against the equivalent symmetric pair collision, gross sliding on a wall, a wall
// moving into a resting sphere, the weight of a settled packing carried by the floor,
// wall history carried across reordering, a restart while touching walls, and no contacts
// through a walled axis.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/dem/walls.hpp"
#include "core/io/output.hpp"
#include "kernels/dem/dem_system.hpp"
#include "scenarios/collisions/impact.hpp"
#include "scenarios/common/restart_file.hpp"
#include "tests/exec_spaces.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// Linear law with its own wall entry (species slot 1 is the wall).
LinearNormal linear_with_wall(double kn, double gn, double kw, double gw) {
  LinearNormal l = LinearNormal::uniform(kn, gn);
  l.table.p[0][1] = l.table.p[1][0] = {kw, gw};
  return l;
}
// Hertz modulus form; a rigid wall (E = inf) drops its term of 1/E*.
HertzNormal hertz_with_wall(double E, double nu, double E_wall, double nu_wall) {
  HertzNormal h{
      PairTable<HertzNormal::Params>::uniform(HertzNormal::modulus_form(E, nu, E, nu, 0))};
  h.table.p[0][1] = h.table.p[1][0] = HertzNormal::modulus_form(E, nu, E_wall, nu_wall, 0);
  return h;
}
double sphere_mass(double a, double rho) { return rho * 4.0 / 3.0 * M_PI * a * a * a; }
}  // namespace

template <class T>
class WallTest : public ::testing::Test {};
TYPED_TEST_SUITE(WallTest, granular::testing::ExecSpaces);

TYPED_TEST(WallTest, WallMotionFollowsItsTableAndVelocity) {
  WallSpec w;
  w.normal[2] = 2.0;  // normalised by validate
  w.point[2] = 10.0;
  w.motion = WallMotion::Table;
  w.table_t = {0.0, 1.0, 3.0};
  w.table_u = {0.0, -2.0, -1.0};
  w.validate("walls.top");
  double x[3], v[3];
  w.state(0.5, x, v);
  EXPECT_DOUBLE_EQ(x[2], 9.0);
  EXPECT_DOUBLE_EQ(v[2], -2.0);
  w.state(2.0, x, v);
  EXPECT_DOUBLE_EQ(x[2], 8.5);
  EXPECT_DOUBLE_EQ(v[2], 0.5);
  w.state(5.0, x, v);  // held at the last point
  EXPECT_DOUBLE_EQ(x[2], 9.0);
  EXPECT_DOUBLE_EQ(v[2], 0.0);
  w.motion = WallMotion::Velocity;
  w.velocity[0] = 0.25;
  w.state(4.0, x, v);
  EXPECT_DOUBLE_EQ(x[0], 1.0);
  EXPECT_DOUBLE_EQ(x[2], 10.0);
  WallSpec bad;
  bad.motion = WallMotion::Table;
  bad.table_t = {0.0, 0.0};
  bad.table_u = {0.0, 1.0};
  EXPECT_THROW(bad.validate("walls.bad"), InputError);
  bad.normal[0] = bad.normal[1] = bad.normal[2] = 0.0;
  EXPECT_THROW(bad.validate("walls.bad"), InputError);
}

TYPED_TEST(WallTest, ElasticHertzImpactOnRigidWallMatchesClosedForms) {
  // Elastic Hertz with R* = a, m* = m and E* = E/(1 - nu^2) (rigid wall): duration
  // t_c = (2 delta_max / v) Int_0^1 (1 - x^{5/2})^{-1/2} dx, delta_max = (15 m v^2 /
  // (16 E* sqrt(R)))^{2/5}, F_max = (4/3) E* sqrt(R) delta_max^{3/2}.
  const double E = 1e4, nu = 0.3, a = 1.0, rho = 2.0, v = 0.01;
  const ContactModel<HertzNormal> model{hertz_with_wall(E, nu, kInf, 0.0), {}, {}};
  const double estar = E / (1 - nu * nu), m = sphere_mass(a, rho);
  const double dmax = std::pow(15.0 * m * v * v / (16.0 * estar * std::sqrt(a)), 0.4);
  const double integral = std::tgamma(0.4) * std::tgamma(0.5) / std::tgamma(0.9) / 2.5;
  const double tc = 2.0 * dmax / v * integral;
  ImpactSetup s;
  s.radius1 = a, s.density1 = rho, s.speed = v, s.dt = tc / 4000;
  const auto r = impact<TypeParam>(model, s);
  ASSERT_TRUE(r.separated);
  EXPECT_NEAR(r.duration / tc, 1.0, 1e-4);
  EXPECT_NEAR(r.max_overlap / dmax, 1.0, 1e-5);
  EXPECT_NEAR(r.max_normal_force / (4.0 / 3.0 * estar * std::sqrt(a) * std::pow(dmax, 1.5)), 1.0,
              1e-5);
  EXPECT_NEAR(r.restitution_normal, 1.0, 1e-6);
  // The rigid wall's E* is exact (not a large number): a stiff but finite wall is softer.
  const ContactModel<HertzNormal> soft{hertz_with_wall(E, nu, 1e3 * E, 0.0), {}, {}};
  const auto rs = impact<TypeParam>(soft, s);
  EXPECT_GT(rs.max_overlap, r.max_overlap * (1 + 1e-4));
}

TYPED_TEST(WallTest, SphereOnRigidWallIsHalfOfSymmetricPairCollision) {
  // Two equal spheres meeting at +-v see their mid-plane as a rigid wall: the Hertz
  // rigid-wall contact (E*_wall = 2 E*_pair, R* = a = 2 R*_pair, m* = m = 2 m*_pair) at v is
  // the pair collision at relative speed 2 v with half the overlap and the same force.
  const double E = 1e4, nu = 0.25, a = 0.8, rho = 3.0, v = 0.02;
  const ContactModel<HertzNormal> model{hertz_with_wall(E, nu, kInf, 0.0), {}, {}};
  ImpactSetup w;
  w.radius1 = a, w.density1 = rho, w.speed = v, w.dt = 2e-3;
  ImpactSetup p = w;
  p.wall = false, p.radius2 = a, p.density2 = rho, p.speed = 2 * v;
  const auto rw = impact<TypeParam>(model, w);
  const auto rp = impact<TypeParam>(model, p);
  ASSERT_TRUE(rw.separated && rp.separated);
  EXPECT_NEAR(rw.duration, rp.duration, 1e-6 * rp.duration);
  EXPECT_NEAR(2 * rw.max_overlap, rp.max_overlap, 1e-9 * rp.max_overlap);
  EXPECT_NEAR(rw.max_normal_force, rp.max_normal_force, 1e-9 * rp.max_normal_force);
  EXPECT_NEAR(rw.restitution_normal, rp.restitution_normal, 1e-9);
  // The linear law's harmonic rule has the same rigid limit: a wall of stiffness 2 k_n.
  const double kn = 50.0, gn = 0.3;
  const ContactModel<LinearNormal> lin{linear_with_wall(kn, gn, 2 * kn, 2 * gn), {}, {}};
  const auto lw = impact<TypeParam>(lin, w);
  const auto lp = impact<TypeParam>(lin, p);
  EXPECT_NEAR(lw.duration, lp.duration, 1e-6 * lp.duration);
  EXPECT_NEAR(lw.restitution_normal, lp.restitution_normal, 1e-9);
  const double m = sphere_mass(a, rho);  // closed forms of the linear law with m* = m
  const double eta = 2 * gn / (2 * m), omega = std::sqrt(2 * kn / m - eta * eta);
  // The measured e carries the integrator's error at 400 steps per contact.
  EXPECT_NEAR(lw.restitution_normal, std::exp(-eta * M_PI / omega), 3e-4);
  EXPECT_NEAR(lw.duration, M_PI / omega, 1e-3 * M_PI / omega);
}

TYPED_TEST(WallTest, GrossSlidingOnWallTransfersMuTimesOnePlusETimesNormalImpulse) {
  // A spinning sphere whose contact point slides for the whole impact: tangential impulse
  // mu (1 + e) m v_n, spin change (5/2) mu (1 + e) v_n / a (levers a - delta/2: the
  // overlap is kept below 1e-3 a, so the spin matches to that order). Undamped (e = 1):
  // with a dashpot the normal force turns tensile at the end and the Coulomb limit, which
  // uses |f_n|, transfers slightly more than mu times the net normal impulse.
  const double kn = 1e5, gn = 0.0, mu = 0.2, a = 1.0, rho = 1.0, v = 0.01;
  using Model = ContactModel<LinearNormal, CoulombTangential>;
  const Model model{
      linear_with_wall(kn, gn, kn, gn), CoulombTangential::uniform(8e4, 0, mu, mu), {}};
  ImpactSetup s;
  s.radius1 = a, s.density1 = rho, s.speed = v, s.angle = 0.3;
  s.spin[1] = -20 * mu * v / a;  // contact point moves along +x, faster than the centre
  const double m = sphere_mass(a, rho);
  const double eta = gn / (2 * m), omega = std::sqrt(kn / m - eta * eta);
  s.dt = M_PI / omega / 2000;
  const auto r = impact<TypeParam>(model, s);
  ASSERT_TRUE(r.separated);
  const double vn = r.vn_in, e = std::exp(-eta * M_PI / omega);
  ASSERT_GT(r.vc_in, 3.5 * mu * (1 + e) * vn);  // slides throughout (docs/model_dem.md §10)
  ASSERT_GT(r.vc_out, 0.0);
  ASSERT_LT(r.max_overlap, 1e-3 * a);
  EXPECT_NEAR(r.restitution_normal, e, 1e-4);
  EXPECT_NEAR(-r.impulse_tangential / (mu * r.impulse_normal), 1.0, 1e-9);
  EXPECT_NEAR(-r.impulse_tangential, mu * (1 + e) * m * vn, 2e-4 * mu * m * vn);
  EXPECT_NEAR((r.spin_out - r.spin_in) / (2.5 * mu * (1 + e) * vn / a), 1.0, 2e-3);
}

TYPED_TEST(WallTest, ElasticWallMovingIntoRestingSphereLaunchesItAtTwiceItsSpeed) {
  using Exec = TypeParam;
  const double kn = 1e3, V = 0.01, a = 0.5;
  HostParticles h;
  h.resize(1);
  h.x[0] = 0, h.y[0] = 0, h.z[0] = 2.0, h.radius[0] = a, h.density[0] = 1.0;
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = -5, box.len[d] = 10, box.periodic[d] = false;
  DemParams prm;
  const double m = sphere_mass(a, 1.0);
  prm.dt = M_PI * std::sqrt(m / kn) / 2000, prm.skin = 0.1;
  DemSystem<Exec, ContactModel<LinearNormal>> sys(Particles<Exec>::from_host(h), box,
                                                  {linear_with_wall(kn, 0, kn, 0), {}, {}}, prm);
  // The wall starts a small gap below the sphere: the approach takes gap / V, the contact
  // half a period, and the run ends well after it.
  const double gap = 1e-3, z0 = 2.0 - a - gap;
  WallSpec floor;
  floor.normal[2] = -1, floor.point[2] = z0, floor.motion = WallMotion::Velocity;
  floor.velocity[2] = V;
  sys.set_walls({floor});
  const long steps = static_cast<long>((gap / V + 3 * M_PI * std::sqrt(m / kn)) / prm.dt);
  sys.step(steps);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().v);
  EXPECT_NEAR(v(0, 2), 2 * V, 1e-6 * V);
  EXPECT_NEAR(sys.walls().host()(0).p[2], z0 + V * steps * prm.dt,
              1e-10);  // t summed step by step
}

namespace {
// A frictional, damped pile settling on a floor inside four side walls, under gravity.
template <class Exec>
struct Pile {
  using Model = ContactModel<LinearNormal, CoulombTangential>;
  std::vector<WallSpec> walls;
  PeriodicBox box;
  HostParticles h;
  Pile(int per_side, int layers) {
    const double d = 1.0, L = per_side * 1.1 * d;
    h.resize(per_side * per_side * layers);
    int k = 0;
    for (int l = 0; l < layers; ++l)
      for (int i = 0; i < per_side; ++i)
        for (int j = 0; j < per_side; ++j, ++k) {
          const double wobble = 0.02 * std::sin(1.7 * k);
          h.x[k] = (i + 0.5) * 1.1 * d + wobble, h.y[k] = (j + 0.5) * 1.1 * d - wobble;
          h.z[k] = (l + 0.5) * 1.1 * d;
          h.radius[k] = 0.5 * d * (0.9 + 0.1 * std::cos(2.3 * k)), h.density[k] = 1.0;
        }
    for (int a = 0; a < 3; ++a) box.lo[a] = 0, box.periodic[a] = false;
    box.len[0] = box.len[1] = L, box.len[2] = (layers + 1) * 1.1 * d;
    const double normals[5][3] = {{0, 0, -1}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}};
    const double points[5][3] = {{0, 0, 0}, {0, 0, 0}, {L, 0, 0}, {0, 0, 0}, {0, L, 0}};
    for (int w = 0; w < 5; ++w) {
      WallSpec s;
      s.name = "wall" + std::to_string(w);
      for (int a = 0; a < 3; ++a) s.normal[a] = normals[w][a], s.point[a] = points[w][a];
      walls.push_back(s);
    }
  }
  DemSystem<Exec, Model> system(long rebuild_every, bool sort,
                                WallLayout layout = WallLayout::Auto) const {
    DemParams prm;
    prm.wall_layout = layout;
    prm.dt = 2e-3, prm.skin = 0.1, prm.damping.translational = 0.05,
    prm.rebuild_every = rebuild_every;
    prm.damping.rotational = 0.01, prm.sort = sort, prm.gravity[2] = -1.0;
    const Model model{
        linear_with_wall(1e3, 0.5, 1e3, 0.5), CoulombTangential::uniform(800, 0.1, 0.4, 0.4), {}};
    DemSystem<Exec, Model> sys(Particles<Exec>::from_host(h), box, model, prm);
    sys.set_walls(walls);
    return sys;
  }
};
}  // namespace

TYPED_TEST(WallTest, SettledPileWeighsOnTheFloorAndSideWallsBalance) {
  Pile<TypeParam> pile(4, 3);
  auto sys = pile.system(0, true);
  sys.step(30000);
  const Measurements m = sys.measure();
  auto mass = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().mass);
  double weight = 0;
  for (int i = 0; i < sys.particles().n; ++i) weight += mass(i);
  const auto loads = sys.wall_loads();
  ASSERT_LT(m.ekin, 1e-9 * weight);  // at rest, up to a residual vibration
  double walls[3] = {0, 0, 0};
  for (const auto& l : loads)
    for (int d = 0; d < 3; ++d) walls[d] += l.force[d];
  // Action and reaction, exactly at any instant: the walls receive minus what they give,
  // so their total plus the particles' net force is the weight vector (pair forces cancel;
  // the background damping -gamma_b v acted with the mid-step velocity v - dt f / 2m).
  auto f = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().f);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().v);
  const double gb = sys.params().damping.translational, dt = sys.params().dt;
  double net[3] = {0, 0, 0};
  for (int i = 0; i < sys.particles().n; ++i)
    for (int d = 0; d < 3; ++d) net[d] += f(i, d) + gb * (v(i, d) - 0.5 * dt * f(i, d) / mass(i));
  for (int d = 0; d < 3; ++d)
    EXPECT_NEAR(walls[d] + net[d], d == 2 ? -weight : 0.0, 1e-12 * weight);
  // At rest the walls carry the weight: the floor directly, the side walls through friction.
  EXPECT_NEAR(-walls[2] / weight, 1.0, 1e-4);
  EXPECT_LT(std::fabs(walls[0]) + std::fabs(walls[1]), 1e-4 * weight);
  EXPECT_NEAR(-loads[0].force[2] / weight, 1.0, 0.1);
  EXPECT_GT(loads[0].contacts, 15);
  // The side walls hold the pile in (their forces point outwards).
  EXPECT_LT(loads[1].force[0], 0.0);
  EXPECT_GT(loads[2].force[0], 0.0);
}

TYPED_TEST(WallTest, WallHistorySurvivesReorderingAndRebuildsIdentically) {
  Pile<TypeParam> pile(4, 3);
  // Shove the pile sideways so the wall springs carry load while particles reorder.
  for (int i = 0; i < pile.h.size(); ++i) pile.h.vx[i] = 0.3, pile.h.vy[i] = -0.2;
  auto run = [&](long every, bool sort) {
    auto sys = pile.system(every, sort);
    sys.step(2000);
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().x);
    auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.particles().id);
    std::vector<double> out(3 * x.extent(0));
    for (size_t i = 0; i < x.extent(0); ++i)
      for (int d = 0; d < 3; ++d) out[3 * id(i) + d] = x(i, d);
    return std::make_pair(out, sys.neighbor_list().builds());
  };
  const auto every = run(1, true);
  const auto skin = run(0, false);
  EXPECT_GT(every.second, 1999);
  EXPECT_LT(skin.second, 400);
  double worst = 0;
  for (size_t k = 0; k < every.first.size(); ++k)
    worst = std::max(worst, std::fabs(every.first[k] - skin.first[k]));
  EXPECT_LT(worst, 1e-9);
}

// A state saved while the pile bounces on its walls, restored into another system with the
// same walls, continues bit for bit: the wall springs, the walls' sums and which wall contacts
// stand come back with it, so contacts that end and start again after the restart are
// forgotten and begun as in the run that never stopped. Both layouts of the walls' record.
template <class Exec>
void restored_pile_continues_bitwise(WallLayout layout) {
  SCOPED_TRACE(layout == WallLayout::Rows ? "walls recorded by rows" : "walls summed by blocks");
  Pile<Exec> pile(4, 3);
  for (int i = 0; i < pile.h.size(); ++i) pile.h.vx[i] = 0.4 * std::sin(i), pile.h.vz[i] = -0.5;
  auto contacts = [](const auto& sys) {
    double c = 0;
    for (const auto& l : sys.wall_loads()) c += l.contacts;
    return c;
  };
  auto a = pile.system(0, true, layout);
  for (int k = 0; k < 40 && contacts(a) <= 10; ++k) a.step(250);  // falls onto the floor
  ASSERT_GT(contacts(a), 10) << "the state must hold wall contacts";
  // Through a restart file, as a resumed run does (saved() shares the system's arrays).
  const auto dir = granular::testing::unique_temp_path("granular_wall_restart");
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "restart.h5").string();
  {
    H5Writer w(path);
    write_restart(w, "/r", a);
    w.commit();
  }
  auto b = pile.system(0, true, layout);
  b.step(3);  // moved on: everything must come from the file
  load_restart(H5Reader(path), "/r", b);
  std::filesystem::remove_all(dir);
  double lo = contacts(a), hi = lo;
  for (int k = 0; k < 30; ++k) {  // the wall contacts change while both run
    a.step(100), b.step(100);
    lo = std::min(lo, contacts(a)), hi = std::max(hi, contacts(a));
  }
  EXPECT_GT(hi - lo, 2) << "too few wall contacts ended or began after the restart";
  auto host = [](const auto& v) {
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
    return std::vector<double>(h.data(), h.data() + h.size());
  };
  EXPECT_EQ(host(a.particles().x), host(b.particles().x));
  EXPECT_EQ(host(a.particles().v), host(b.particles().v));
  EXPECT_EQ(host(a.particles().f), host(b.particles().f));
  EXPECT_EQ(host(a.wall_history()), host(b.wall_history()));
  const auto la = a.wall_loads(), lb = b.wall_loads();
  ASSERT_EQ(la.size(), lb.size());
  for (size_t w = 0; w < la.size(); ++w) {
    EXPECT_EQ(la[w].contacts, lb[w].contacts) << "wall " << w;
    for (int d = 0; d < 3; ++d) EXPECT_EQ(la[w].force[d], lb[w].force[d]) << "wall " << w;
  }
}

TYPED_TEST(WallTest, StateRestoredWhileTouchingWallsContinuesBitwise) {
  for (const WallLayout layout : {WallLayout::Blocks, WallLayout::Rows})
    restored_pile_continues_bitwise<TypeParam>(layout);
}

// The walls' loads summed by blocks of particles as the wall pass goes (the host's layout)
// are the loads summed from one row per (particle, wall) (the device's layout), bit for bit,
// and so is the motion: a pile of 400 spheres (two blocks of 256, reordered at rebuilds) falls
// and bounces on its floor and side walls, its wall contacts starting and ending.
TYPED_TEST(WallTest, WallLoadsSummedByBlocksEqualThoseOfPerParticleRowsBitwise) {
  Pile<TypeParam> pile(10, 4);
  for (int i = 0; i < pile.h.size(); ++i) pile.h.vx[i] = 0.3 * std::sin(i), pile.h.vz[i] = -0.4;
  auto blocks = pile.system(0, true, WallLayout::Blocks);
  auto rows = pile.system(0, true, WallLayout::Rows);
  double lo = kInf, hi = 0;
  for (int k = 0; k < 24; ++k) {
    blocks.step(150), rows.step(150);
    const auto lb = blocks.wall_loads(), lr = rows.wall_loads();
    ASSERT_EQ(lb.size(), 5u);
    ASSERT_EQ(lr.size(), 5u);
    double c = 0;
    for (size_t w = 0; w < lb.size(); ++w) {
      EXPECT_EQ(lb[w].contacts, lr[w].contacts) << "wall " << w << ", round " << k;
      EXPECT_EQ(lb[w].energy, lr[w].energy) << "wall " << w << ", round " << k;
      EXPECT_EQ(lb[w].max_overlap, lr[w].max_overlap) << "wall " << w << ", round " << k;
      for (int d = 0; d < 3; ++d) {
        EXPECT_EQ(lb[w].force[d], lr[w].force[d]) << "wall " << w << ", round " << k;
        EXPECT_EQ(lb[w].torque[d], lr[w].torque[d]) << "wall " << w << ", round " << k;
      }
      c += lb[w].contacts;
    }
    lo = std::min(lo, c), hi = std::max(hi, c);
    EXPECT_EQ(blocks.measure().epot, rows.measure().epot) << "round " << k;
  }
  EXPECT_GT(lo, 10) << "the pile must touch its walls in every round";
  EXPECT_GT(hi - lo, 50) << "too few wall contacts began or ended";  // 13 to 163 when written
  EXPECT_GT(blocks.neighbor_list().builds(), 2) << "no reordering between the rounds";
  auto host = [](const auto& v) {
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
    return std::vector<double>(h.data(), h.data() + h.size());
  };
  EXPECT_EQ(host(blocks.particles().x), host(rows.particles().x));
  EXPECT_EQ(host(blocks.particles().f), host(rows.particles().f));
  EXPECT_EQ(host(blocks.wall_history()), host(rows.wall_history()));
}

// A restart file of an earlier version (one row per particle and wall, walls/record) is
// refused with a message that names it, before anything is read.
TEST(WallRestart, FileWithPerParticleWallRowsIsRefusedWithAClearMessage) {
  const auto dir = granular::testing::unique_temp_path("granular_wall_restart_old");
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "restart.h5").string();
  {
    H5Writer w(path);
    w.write("/r/walls/record", std::vector<double>(18, 0.0));
    w.commit();
  }
  using System =
      DemSystem<Kokkos::DefaultHostExecutionSpace, Pile<Kokkos::DefaultHostExecutionSpace>::Model>;
  try {
    read_restart<System>(H5Reader(path), "/r");
    ADD_FAILURE() << "an earlier version's restart file was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("walls/record"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("earlier version"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TYPED_TEST(WallTest, NoContactAcrossAWalledAxis) {
  using Exec = TypeParam;
  HostParticles h;
  h.resize(2);
  h.x = {1.0, 1.0}, h.y = {1.0, 1.0}, h.z = {0.45, 9.55};  // touching only through z images
  h.radius = {0.5, 0.5}, h.density = {1.0, 1.0};
  PeriodicBox box;
  for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = d == 2 ? 10.0 : 6.0;
  DemParams prm;
  prm.dt = 1e-3, prm.skin = 0.1;
  const ContactModel<LinearNormal> model{LinearNormal::uniform(100, 0), {}, {}};
  DemSystem<Exec, ContactModel<LinearNormal>> periodic(Particles<Exec>::from_host(h), box, model,
                                                       prm);
  EXPECT_EQ(periodic.measure().contacts, 1.0);
  box.periodic[2] = false;
  DemSystem<Exec, ContactModel<LinearNormal>> walled(Particles<Exec>::from_host(h), box, model,
                                                     prm);
  EXPECT_EQ(walled.measure().contacts, 0.0);
  // ... while x stays periodic: a particle leaving through x re-enters.
  h.z = {0.45, 5.0};
  h.vx = {-10.0, 0.0};
  DemSystem<Exec, ContactModel<LinearNormal>> mixed(Particles<Exec>::from_host(h), box, model, prm);
  mixed.step(200);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mixed.particles().x);
  EXPECT_NEAR(x(0, 0), 1.0 - 2.0 + 6.0, 1e-9);
}
