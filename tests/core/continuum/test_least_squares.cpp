// Levenberg-Marquardt and linear least squares: parameters and their standard errors
// against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "core/continuum/least_squares.hpp"

using namespace granular;

// Noise-free data of a power law with offset: the fit must return the generating
// parameters, from a start far from them.
TEST(LeastSquares, LevenbergMarquardtRecoversAPowerLawExactly) {
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(30, 0.01, 0.25), y(30);
  for (int i = 0; i < 30; ++i) y[i] = 6.0 + 9.5 * std::pow(x[i], 0.4);
  auto r = [&](const Eigen::VectorXd& p) {
    Eigen::VectorXd out(30);
    for (int i = 0; i < 30; ++i) out[i] = p[0] + p[1] * std::pow(x[i], p[2]) - y[i];
    return out;
  };
  LeastSquaresOptions o;
  o.lower = {-100, -100, 0.05};
  o.upper = {100, 100, 3};
  const LeastSquaresFit fit = levenberg_marquardt(r, Eigen::Vector3d(1, 1, 1), o);
  EXPECT_TRUE(fit.converged);
  EXPECT_NEAR(fit.params[0], 6.0, 1e-7);
  EXPECT_NEAR(fit.params[1], 9.5, 1e-7);
  EXPECT_NEAR(fit.params[2], 0.4, 1e-8);
  EXPECT_LT(fit.rms, 1e-9);
}

// Straight line with scattered data: slope and intercept errors from the textbook formulas
// s / sqrt(Sxx) and s sqrt(1/n + xbar^2 / Sxx); LM on the same model must agree with the
// linear solution, errors included (its Jacobian is exact for a linear model).
TEST(LeastSquares, StandardErrorsMatchTheClosedFormsOfAStraightLine) {
  const int n = 12;
  Eigen::MatrixXd X(n, 2);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    X(i, 0) = 1, X(i, 1) = 0.5 * i;
    y[i] = 2.0 - 0.7 * X(i, 1) + 0.1 * std::sin(3.0 * i);  // deterministic "noise"
  }
  const LeastSquaresFit lin = linear_least_squares(X, y);
  const double xbar = X.col(1).mean();
  const double Sxx = (X.col(1).array() - xbar).square().sum();
  const double s = std::sqrt(lin.rss / (n - 2));
  EXPECT_NEAR(lin.std_error[1], s / std::sqrt(Sxx), 1e-12);
  EXPECT_NEAR(lin.std_error[0], s * std::sqrt(1.0 / n + xbar * xbar / Sxx), 1e-12);
  EXPECT_EQ(lin.dof, n - 2);
  auto r = [&](const Eigen::VectorXd& p) -> Eigen::VectorXd { return X * p - y; };
  const LeastSquaresFit nl = levenberg_marquardt(r, Eigen::Vector2d(0, 0));
  EXPECT_NEAR(nl.params[0], lin.params[0], 1e-9);
  EXPECT_NEAR(nl.params[1], lin.params[1], 1e-9);
  EXPECT_NEAR(nl.std_error[0], lin.std_error[0], 1e-7);
  EXPECT_NEAR(nl.std_error[1], lin.std_error[1], 1e-7);
}
