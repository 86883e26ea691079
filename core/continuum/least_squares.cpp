// Levenberg-Marquardt and linear least squares with parameter covariance.
#include "core/continuum/least_squares.hpp"

#include <algorithm>
#include <cmath>

#include "core/run/error.hpp"

namespace granular {

namespace {

Eigen::MatrixXd jacobian(const ResidualFunction& residual, const Eigen::VectorXd& p,
                         const LeastSquaresOptions& o, int m) {
  Eigen::MatrixXd J(m, p.size());
  for (int k = 0; k < p.size(); ++k) {
    const double h = 1e-6 * std::max(1.0, std::abs(p[k]));
    Eigen::VectorXd a = p, b = p;
    a[k] += h, b[k] -= h;
    // One-sided at a bound, so the residual is never evaluated outside the domain.
    if (!o.upper.empty() && a[k] > o.upper[k]) a[k] = p[k];
    if (!o.lower.empty() && b[k] < o.lower[k]) b[k] = p[k];
    J.col(k) = (residual(a) - residual(b)) / (a[k] - b[k]);
  }
  return J;
}

void project(Eigen::VectorXd& p, const LeastSquaresOptions& o) {
  for (int k = 0; k < p.size(); ++k) {
    if (!o.lower.empty()) p[k] = std::max(p[k], o.lower[k]);
    if (!o.upper.empty()) p[k] = std::min(p[k], o.upper[k]);
  }
}

void statistics(LeastSquaresFit& fit, const Eigen::MatrixXd& J) {
  fit.points = static_cast<int>(fit.residuals.size());
  fit.dof = fit.points - static_cast<int>(fit.params.size());
  fit.rss = fit.residuals.squaredNorm();
  fit.rms = std::sqrt(fit.rss / std::max(1, fit.points));
  const double s2 = fit.dof > 0 ? fit.rss / fit.dof : NAN;
  // Pseudo-inverse: a parameter the data cannot determine shows up as a huge error, not as
  // a failed inversion.
  const Eigen::MatrixXd JtJ = J.transpose() * J;
  fit.covariance = s2 * JtJ.completeOrthogonalDecomposition().pseudoInverse();
  fit.std_error = fit.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
}

}  // namespace

LeastSquaresFit levenberg_marquardt(const ResidualFunction& residual, Eigen::VectorXd p,
                                    const LeastSquaresOptions& o) {
  const int n = static_cast<int>(p.size());
  if ((!o.lower.empty() && static_cast<int>(o.lower.size()) != n) ||
      (!o.upper.empty() && static_cast<int>(o.upper.size()) != n))
    throw InputError("least squares: bounds must have one entry per parameter");
  project(p, o);
  LeastSquaresFit fit;
  Eigen::VectorXd r = residual(p);
  const int m = static_cast<int>(r.size());
  if (m < n) throw InputError("least squares: fewer data points than parameters");
  double cost = r.squaredNorm(), lambda = 1e-3;
  for (fit.iterations = 0; fit.iterations < o.max_iterations; ++fit.iterations) {
    const Eigen::MatrixXd J = jacobian(residual, p, o, m);
    const Eigen::MatrixXd A = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
    bool improved = false;
    double new_cost = cost;
    // Marquardt's scaling by diag(A) makes the damping independent of parameter units.
    for (int tries = 0; tries < 30 && !improved; ++tries) {
      Eigen::MatrixXd D = A;
      for (int k = 0; k < n; ++k) D(k, k) += lambda * std::max(A(k, k), 1e-300);
      Eigen::VectorXd q = p - D.ldlt().solve(g);
      project(q, o);
      const Eigen::VectorXd rq = residual(q);
      new_cost = rq.allFinite() ? rq.squaredNorm() : INFINITY;
      if (new_cost < cost) {
        p = q, r = rq, improved = true;
        lambda = std::max(lambda / 10, 1e-15);
      } else {
        lambda *= 10;
      }
    }
    if (!improved) {  // no step lowers the cost: at a minimum to machine precision
      fit.converged = true;
      break;
    }
    const double change = (cost - new_cost) / std::max(cost, 1e-300);
    cost = new_cost;
    if (change < o.tolerance) {
      fit.converged = true;
      break;
    }
  }
  fit.params = p;
  fit.residuals = r;
  statistics(fit, jacobian(residual, p, o, m));
  fit.at_bound.assign(n, false);
  for (int k = 0; k < n; ++k)
    fit.at_bound[k] =
        (!o.lower.empty() && p[k] <= o.lower[k]) || (!o.upper.empty() && p[k] >= o.upper[k]);
  return fit;
}

LeastSquaresFit linear_least_squares(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) {
  if (X.rows() < X.cols()) throw InputError("least squares: fewer data points than parameters");
  LeastSquaresFit fit;
  fit.params = X.colPivHouseholderQr().solve(y);
  fit.residuals = X * fit.params - y;
  fit.converged = true;
  statistics(fit, X);
  fit.at_bound.assign(X.cols(), false);
  return fit;
}

}  // namespace granular
