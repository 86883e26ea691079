#include "core/master_equation.hpp"

#include <cmath>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

#include "core/error.hpp"

namespace granular {

namespace {

// For a fixed rate z both models are linear in y: the best y is a projection, so the fit
// reduces to a one-dimensional search over z (log grid, then golden section).
template <class Basis, class Target>
ExpFit fit_one_rate(const std::vector<double>& t, Basis basis, Target target) {
  auto solve = [&](double z) {
    double num = 0, den = 0;
    for (size_t i = 0; i < t.size(); ++i) {
      const double g = basis(z, t[i]);
      num += g * target(z, t[i], i);
      den += g * g;
    }
    ExpFit f;
    f.z = z;
    f.y = den > 0 ? num / den : 0.0;
    for (size_t i = 0; i < t.size(); ++i) {
      const double d = f.y * basis(z, t[i]) - target(z, t[i], i);
      f.residual += d * d;
    }
    return f;
  };
  const double tmax = t.back() > 0 ? t.back() : 1.0;
  const double zlo = 1e-4 / tmax, zhi = 1e3 / tmax;
  const int grid = 241;
  int best = 0;
  std::vector<ExpFit> g(grid);
  for (int k = 0; k < grid; ++k) {
    g[k] = solve(zlo * std::pow(zhi / zlo, double(k) / (grid - 1)));
    if (g[k].residual < g[best].residual) best = k;
  }
  double a = std::log(g[std::max(best - 1, 0)].z), b = std::log(g[std::min(best + 1, grid - 1)].z);
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = b - phi * (b - a), x2 = a + phi * (b - a);
  ExpFit f1 = solve(std::exp(x1)), f2 = solve(std::exp(x2));
  for (int it = 0; it < 100 && b - a > 1e-13; ++it) {
    if (f1.residual < f2.residual) {
      b = x2, x2 = x1, f2 = f1, x1 = b - phi * (b - a), f1 = solve(std::exp(x1));
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + phi * (b - a), f2 = solve(std::exp(x2));
    }
  }
  ExpFit best_fit = f1.residual < f2.residual ? f1 : f2;
  return best_fit.residual <= g[best].residual ? best_fit : g[best];
}

void check_window(const BandSeries& d, FitWindow w) {
  const int T = static_cast<int>(d.times.size());
  if (w.first < 0 || w.last >= T || w.last - w.first < 1)
    throw InputError("fit window [" + std::to_string(w.first) + ", " + std::to_string(w.last) +
                     "] must hold at least two of the " + std::to_string(T) + " samples");
  if (d.series.empty()) throw InputError("no band series to fit");
}

std::vector<double> window_slice(const std::vector<double>& x, FitWindow w) {
  return std::vector<double>(x.begin() + w.first, x.begin() + w.last + 1);
}

std::vector<double> row_slice(const Eigen::MatrixXd& m, int row, FitWindow w) {
  std::vector<double> out;
  for (int i = w.first; i <= w.last; ++i) out.push_back(m(row, i));
  return out;
}

}  // namespace

ExpFit fit_decay(const std::vector<double>& t, const std::vector<double>& e) {
  // e - exp(-z t) = y (1 - exp(-z t))
  return fit_one_rate(
      t, [](double z, double ti) { return 1.0 - std::exp(-z * ti); },
      [&](double z, double ti, size_t i) { return e[i] - std::exp(-z * ti); });
}

ExpFit fit_rise(const std::vector<double>& t, const std::vector<double>& e) {
  return fit_one_rate(
      t, [](double z, double ti) { return 1.0 - std::exp(-z * ti); },
      [&](double, double, size_t i) { return e[i]; });
}

Eigen::MatrixXd fit_transfer_matrix_nonlinear(const BandSeries& d, FitWindow w) {
  check_window(d, w);
  const int B = static_cast<int>(d.series.size());
  const auto t = window_slice(d.times, w);
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(B, B);
  for (int s = 0; s < B; ++s)
    for (int r = 0; r < B; ++r) {
      const auto e = row_slice(d.series[s], r, w);
      if (r == s) {
        const ExpFit f = fit_decay(t, e);
        Q(s, s) = -f.z * (1.0 - f.y);
      } else {
        const ExpFit f = fit_rise(t, e);
        Q(r, s) = f.y * f.z;
      }
    }
  return Q;
}

Eigen::MatrixXd fit_transfer_matrix_linear(const BandSeries& d, FitWindow w) {
  check_window(d, w);
  const int B = static_cast<int>(d.series.size());
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(B, B);
  double tt = 0;
  for (int i = w.first; i <= w.last; ++i) tt += d.times[i] * d.times[i];
  for (int s = 0; s < B; ++s)
    for (int r = 0; r < B; ++r) {
      double te = 0;
      for (int i = w.first; i <= w.last; ++i)
        te += d.times[i] * (r == s ? 1.0 - d.series[s](r, i) : d.series[s](r, i));
      Q(r, s) = (r == s ? -1.0 : 1.0) * te / tt;
    }
  return Q;
}

Eigen::MatrixXd balance_columns(const Eigen::MatrixXd& Q) {
  Eigen::MatrixXd out = Q;
  for (Eigen::Index s = 0; s < Q.cols(); ++s) out(s, s) = Q(s, s) - Q.col(s).sum();
  return out;
}

Eigen::MatrixXd solve_master_equation(const Eigen::MatrixXd& Q, const Eigen::VectorXd& e0,
                                      const std::vector<double>& times) {
  Eigen::MatrixXd out(Q.rows(), static_cast<Eigen::Index>(times.size()));
  for (size_t i = 0; i < times.size(); ++i) {
    const Eigen::MatrixXd Qt = Q * times[i];
    out.col(static_cast<Eigen::Index>(i)) = Qt.exp() * e0;
  }
  return out;
}

}  // namespace granular
