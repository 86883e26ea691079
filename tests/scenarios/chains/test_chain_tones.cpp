// The chain_tones scene against closed forms: on an ordered chain a standing wave is an
// eigenmode of the linearized chain, so its displacement map is u0 sin(k p) cos(omega t) with
// omega = 2 sqrt(3/2) sin(k/2) and its energy stays in its band; the initial energy is a
// quadratic form of u0 (amplitude check exact), and the ensemble's energy is kept to
// Verlet's O(dt^2) whatever the amplitude.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/io/output.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;

namespace {
const char* kScene = R"(
scene = "chain_tones"
[chain]
beads = 63
boundary = "fixed"
force = "hertz"
[disorder]
xi = [0.0, 0.3]
realizations = 6
seed = 1
min_mass = 0.05
[bands]
count = 8
[wave]
tones = [3, 20]
u0 = [0.001, 0.0001]
[fit]
tone = 20
[time]
dt = 0.02
sample_every = 1.0
samples = 40
)";

// As the CLI does: the `scene` key picks the driver before the driver reads the rest.
SceneFile tones_scene(const std::string& text, const std::string& name) {
  SceneFile s = SceneFile::parse(text, name);
  EXPECT_EQ(s.text("scene"), "chain_tones");
  return s;
}

struct TonesRun {
  std::string dir;
  TonesRun() {
    dir = granular::testing::temp_dir("chain_tones");
    RunOptions opts;
    opts.out_dir = dir, opts.progress = false, opts.charts = false;
    run_chain_tones(tones_scene(kScene, "tones.toml"), opts);
  }
  ~TonesRun() { std::filesystem::remove_all(dir); }
  H5Reader h5() const { return H5Reader(dir + "/results.h5"); }
};
const TonesRun& tones_run() {
  static const TonesRun run;
  return run;
}
}  // namespace

TEST(ChainTones, OrderedChainStandingWaveFollowsTheEigenmodeInClosedForm) {
  const H5Reader h5 = tones_run().h5();
  const std::vector<double> t = h5.reals("/xi_0/times");
  const std::vector<double> u = h5.reals("/xi_0/tone_3_u0_0.0001/u_one");
  const int N = 63, L = 64, T = static_cast<int>(t.size());
  ASSERT_EQ(u.size(), static_cast<size_t>(N * T));
  const double k = 2 * M_PI * 3 / L, omega = 2 * std::sqrt(1.5) * std::sin(k / 2);
  double worst = 0;
  for (int p = 0; p < N; ++p)
    for (int s = 0; s < T; ++s) {
      const double exact = 1e-4 * std::sin(k * (p + 1)) * std::cos(omega * t[s]);
      worst = std::max(worst, std::abs(u[p * T + s] - exact));
    }
  // Hertz nonlinearity at u0 = 1e-4 and Verlet's O(dt^2) phase error: 3e-5 of u0 measured.
  EXPECT_LT(worst, 2e-4 * 1e-4);
  EXPECT_GT(t.back(), 2 * M_PI / omega);  // at least one full period was compared
}

TEST(ChainTones, OrderedChainKeepsTheToneInItsBandAndDisorderSpreadsIt) {
  const H5Reader h5 = tones_run().h5();
  const int B = 8, T = static_cast<int>(h5.reals("/xi_0/times").size());
  const int band = (20 - 1) * B / 32;  // tone 20 of L = 64 sites
  const std::vector<double> ordered = h5.reals("/xi_0/tone_20_u0_0.0001/bands_mean");
  const std::vector<double> disordered = h5.reals("/xi_1/tone_20_u0_0.0001/bands_mean");
  for (int s = 0; s < T; ++s) EXPECT_GT(ordered[band * T + s], 1 - 1e-6) << "sample " << s;
  EXPECT_LT(disordered[band * T + T - 1], 0.6);  // xi = 0.3 moves energy out (0.42 left)
  for (int s = 0; s < T; ++s) {
    double sum = 0;
    for (int r = 0; r < B; ++r) sum += disordered[r * T + s];
    EXPECT_NEAR(sum, 1.0, 1e-12);  // normalized band energies
  }
}

TEST(ChainTones, AmplitudesDifferOnlyInAmplitudeAndEnergyIsKeptToVerletOrder) {
  const H5Reader h5 = tones_run().h5();
  for (const char* xi : {"/xi_0", "/xi_1"}) {
    const std::string g = std::string(xi) + "/tone_20_u0_";
    const auto e1 = h5.reals(g + "0.001/total_mean"), e2 = h5.reals(g + "0.0001/total_mean");
    // The initial state is at rest: its energy is the linearized potential, quadratic in u0.
    EXPECT_NEAR(e1[0] / e2[0], 100.0, 1e-10);
    // Velocity Verlet keeps a harmonic mode's energy to a relative oscillation of about
    // (omega dt)^2 / 4 (omega of tone 20: 2 sqrt(3/2) sin(k/2), dt = 0.02); in the linear
    // regime that oscillation does not depend on the amplitude.
    const double omega = 2 * std::sqrt(1.5) * std::sin(M_PI * 20 / 64), dt = 0.02;
    double drift1 = 0, drift2 = 0;
    for (size_t s = 0; s < e1.size(); ++s)
      drift1 = std::max(drift1, std::abs(e1[s] / e1[0] - 1)),
      drift2 = std::max(drift2, std::abs(e2[s] / e2[0] - 1));
    EXPECT_LT(drift2, 0.5 * (omega * dt) * (omega * dt)) << xi;
    EXPECT_NEAR(drift1 / drift2, 1.0, 0.05) << xi;
    const auto b1 = h5.reals(g + "0.001/bands_mean"), b2 = h5.reals(g + "0.0001/bands_mean");
    double worst = 0;
    for (size_t i = 0; i < b1.size(); ++i) worst = std::max(worst, std::abs(b1[i] - b2[i]));
    EXPECT_LT(worst, 1e-4) << xi;  // the nonlinearity is O(u0): 2e-5 measured at xi = 0.3
  }
}

TEST(ChainTones, ToneOutsideTheLatticeNamesTheKey) {
  std::string text = kScene;
  text.replace(text.find("tones = [3, 20]"), 15, "tones = [3, 40]");
  RunOptions opts;
  opts.check_only = true;
  try {
    run_chain_tones(tones_scene(text, "bad_tones.toml"), opts);
    FAIL() << "a tone above L/2 was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("wave.tones"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad_tones.toml"), std::string::npos) << e.what();
  }
}
