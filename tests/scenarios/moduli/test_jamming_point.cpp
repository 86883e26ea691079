// The jamming-density fit on synthetic unloading series with a known root: linear contacts
// (P* ∝ phi - phi_J) and Hertz (P ∝ (phi - phi_J)^(3/2)), samples above the fit window and
// on the compression branch left out, the bracketing densities, and too few points.
#include <gtest/gtest.h>

#include <cmath>

#include "scenarios/moduli/jamming_point.hpp"

using namespace granular;

namespace {

// Compression from 0.5 to 0.8 (direction +1), then unloading to 0.55 (direction -1), of one
// variant; the pressure follows c (phi - phi_j)^alpha above phi_j and is zero below.
std::map<std::string, std::vector<double>> series(double phi_j, double alpha, double c,
                                                  double shift_up) {
  std::map<std::string, std::vector<double>> s;
  auto add = [&](double phi, double dir, double pj) {
    const double p = phi > pj ? c * std::pow(phi - pj, alpha) : 0.0;
    s["phi"].push_back(phi), s["direction"].push_back(dir), s["variant"].push_back(0);
    s["pressure_star"].push_back(p), s["pressure"].push_back(p);
    s["z_corrected"].push_back(p > 0 ? 4 + 10 * (phi - pj) : 0.0);
  };
  for (double phi = 0.5; phi < 0.8; phi += 0.001) add(phi, 1, phi_j + shift_up);
  for (double phi = 0.8; phi > 0.55; phi -= 0.0005) add(phi, -1, phi_j);
  return s;
}

}  // namespace

TEST(JammingPoint, LinearUnloadingSeriesGivesItsRoot) {
  // The loading branch jams later (shift): it must not enter the fit.
  const auto j = jamming_points(series(0.6413, 1.0, 0.5, 0.02), "pressure_star", 1.0, 1e-3);
  ASSERT_EQ(j.size(), 1u);
  EXPECT_NEAR(j[0].phi_j, 0.6413, 1e-10);
  EXPECT_GE(j[0].points, 4);
  EXPECT_LT(j[0].phi_j_stderr, 1e-9);
  // 0 < P* <= 1e-3 is phi - phi_J <= 2e-3: four samples 0.0005 apart at most.
  EXPECT_LE(j[0].points, 4);
  EXPECT_GT(j[0].phi_lowest_jammed, 0.6413);
  EXPECT_LT(j[0].phi_lowest_jammed, 0.6413 + 0.0005 + 1e-12);
  EXPECT_LT(j[0].phi_highest_unjammed, 0.6413);
  EXPECT_GT(j[0].phi_highest_unjammed, 0.6413 - 0.0005 - 1e-12);
}

TEST(JammingPoint, HertzUnloadingSeriesGivesItsRootThroughThreeHalvesPower) {
  const auto j = jamming_points(series(0.6021, 1.5, 2.0e3, 0.0), "pressure", 1.5, 5.0);
  ASSERT_EQ(j.size(), 1u);
  EXPECT_NEAR(j[0].phi_j, 0.6021, 1e-9);
  // The same points read as linear (the wrong exponent) miss the root.
  const auto wrong = jamming_points(series(0.6021, 1.5, 2.0e3, 0.0), "pressure", 1.0, 5.0);
  EXPECT_GT(std::fabs(wrong[0].phi_j - 0.6021), 1e-4);
}

TEST(JammingPoint, TooFewSamplesInTheWindowGiveNoRoot) {
  const auto j = jamming_points(series(0.6413, 1.0, 0.5, 0.0), "pressure_star", 1.0, 1e-4);
  ASSERT_EQ(j.size(), 1u);
  EXPECT_LT(j[0].points, 4);
  EXPECT_TRUE(std::isnan(j[0].phi_j));
  EXPECT_FALSE(std::isnan(j[0].phi_highest_unjammed));  // the brackets stand without a fit
}
