// Nonlinear least squares by Levenberg-Marquardt (Eigen, host code) with standard errors of
// the fitted parameters from the Jacobian at the optimum: cov = s^2 (J^T J)^-1, s^2 = RSS /
// (m - n). Used to fit the continuum law's constants to the engine's element tests.
#pragma once
#include <Eigen/Dense>
#include <functional>
#include <vector>

namespace granular {

using ResidualFunction = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

struct LeastSquaresOptions {
  int max_iterations = 500;
  double tolerance = 1e-12;  // relative change of the sum of squares that ends the iteration
  // Box bounds per parameter (empty: none); steps are projected into them.
  std::vector<double> lower, upper;
};

struct LeastSquaresFit {
  Eigen::VectorXd params, std_error, residuals;
  Eigen::MatrixXd covariance;
  double rss = 0, rms = 0;  // sum of squared residuals, root mean square residual
  int points = 0, dof = 0, iterations = 0;
  bool converged = false;
  // Parameters sitting on a bound have no meaningful standard error (reported as such).
  std::vector<bool> at_bound;
};

// The Jacobian is by central differences with steps scaled to
// each parameter, so residual functions need no derivatives.
LeastSquaresFit levenberg_marquardt(const ResidualFunction& residual, Eigen::VectorXd start,
                                    const LeastSquaresOptions& options = {});

// Linear least squares y ~ X p with the same statistics (X: one column per parameter).
LeastSquaresFit linear_least_squares(const Eigen::MatrixXd& X, const Eigen::VectorXd& y);

}  // namespace granular
