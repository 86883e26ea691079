#include "core/chain/master_equation.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

#include "core/run/error.hpp"

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

namespace {

// The integral-form data of one fit: per experiment s and sample i of the window,
// D = e_s(t_i) - e_s(t_0) and J = integral of e_s from t_0 to t_i, and the elapsed time.
struct IntegralData {
  std::vector<Eigen::VectorXd> d, j, e0;
  std::vector<double> elapsed;
  std::vector<int> experiment;
};

IntegralData integral_form(const BandSeries& data, FitWindow w) {
  IntegralData out;
  const int B = static_cast<int>(data.series.size());
  for (int s = 0; s < B; ++s) {
    const Eigen::MatrixXd& e = data.series[s];
    Eigen::VectorXd integral = Eigen::VectorXd::Zero(e.rows());
    for (int i = w.first + 1; i <= w.last; ++i) {
      integral += 0.5 * (data.times[i] - data.times[i - 1]) * (e.col(i) + e.col(i - 1));
      out.d.push_back(e.col(i) - e.col(w.first));
      out.j.push_back(integral);
      out.e0.push_back(e.col(w.first));
      out.elapsed.push_back(data.times[i] - data.times[w.first]);
      out.experiment.push_back(s);
    }
  }
  return out;
}

Eigen::MatrixXd with_balanced_diagonal(Eigen::MatrixXd X) {
  X.diagonal().setZero();
  for (Eigen::Index s = 0; s < X.cols(); ++s) X(s, s) = -X.col(s).sum();
  return X;
}

// min 1/2 sum_k |D_k - Q J'_k|^2 over off-diagonal X >= 0, Q = X - diag(column sums of X),
// with J'_k = J_k - elapsed_k f_s e0_k (s: the experiment of equation k); starts from X and returns
// the iterations used.
int fit_rates(const IntegralData& data, const Eigen::VectorXd& f, Eigen::MatrixXd& X) {
  const Eigen::Index B = X.rows();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(B, B), C = Eigen::MatrixXd::Zero(B, B);
  for (size_t k = 0; k < data.d.size(); ++k) {
    const Eigen::VectorXd jk = data.j[k] - data.elapsed[k] * f(data.experiment[k]) * data.e0[k];
    A.noalias() += jk * jk.transpose();
    C.noalias() += data.d[k] * jk.transpose();
  }
  // Q depends on X through a map of norm^2 <= B; the gradient is Lipschitz with B lambda_max(A).
  const double lmax = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues().maxCoeff();
  if (!(lmax > 0)) return 0;
  const double step = 1.0 / (static_cast<double>(B) * lmax);
  auto gradient = [&](const Eigen::MatrixXd& Y) {
    const Eigen::MatrixXd G = with_balanced_diagonal(Y) * A - C;
    Eigen::MatrixXd g(B, B);
    for (Eigen::Index s = 0; s < B; ++s)
      for (Eigen::Index r = 0; r < B; ++r) g(r, s) = r == s ? 0.0 : G(r, s) - G(s, s);
    return g;
  };
  Eigen::MatrixXd prev = X, Y = X;
  double t = 1;
  const int max_iterations = 200000;
  int it = 0;
  for (; it < max_iterations; ++it) {
    Eigen::MatrixXd next = (Y - step * gradient(Y)).cwiseMax(0.0);
    next.diagonal().setZero();
    const double change = (next - X).cwiseAbs().maxCoeff();
    const double scale = std::max(next.cwiseAbs().maxCoeff(), 1e-300);
    // Momentum is dropped whenever it points uphill (adaptive restart, O'Donoghue and
    // Candes): the same minimum, reached in far fewer steps on ill-conditioned data.
    if (((Y - next).array() * (next - X).array()).sum() > 0) t = 1;
    const double t_next = 0.5 * (1 + std::sqrt(1 + 4 * t * t));
    prev = X, X = next;
    Y = X + ((t - 1) / t_next) * (X - prev);
    t = t_next;
    if (change <= 1e-12 * scale) break;
  }
  return it + 1;
}

double integral_rms(const IntegralData& data, const Eigen::MatrixXd& Q, const Eigen::VectorXd& f) {
  double ss = 0;
  long n = 0;
  for (size_t k = 0; k < data.d.size(); ++k) {
    const Eigen::VectorXd jk = data.j[k] - data.elapsed[k] * f(data.experiment[k]) * data.e0[k];
    ss += (data.d[k] - Q * jk).squaredNorm(), n += data.d[k].size();
  }
  return n > 0 ? std::sqrt(ss / n) : 0.0;
}

}  // namespace

GlobalFit fit_transfer_matrix_global(const BandSeries& data, FitWindow w, bool trapped) {
  check_window(data, w);
  const int B = static_cast<int>(data.series.size());
  const IntegralData in = integral_form(data, w);
  GlobalFit out;
  out.trapped = Eigen::VectorXd::Zero(B);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(B, B);
  out.iterations = fit_rates(in, out.trapped, X);
  // Trapped fractions: experiment s starts (almost) wholly in band s, so it traps f_s of its
  // initial energy: D - Q J = -elapsed f_s Q e0. For fixed Q each f_s is a one-dimensional
  // least-squares problem; alternate with the rates until f settles.
  for (int round = 0; trapped && round < 100; ++round) {
    const Eigen::MatrixXd Q = with_balanced_diagonal(X);
    Eigen::VectorXd num = Eigen::VectorXd::Zero(B), den = Eigen::VectorXd::Zero(B);
    for (size_t k = 0; k < in.d.size(); ++k) {
      const int s = in.experiment[k];
      const Eigen::VectorXd r = in.d[k] - Q * in.j[k];
      const Eigen::VectorXd g = -in.elapsed[k] * (Q * in.e0[k]);
      num(s) += r.dot(g), den(s) += g.squaredNorm();
    }
    Eigen::VectorXd f(B);
    for (int s = 0; s < B; ++s) f(s) = den(s) > 0 ? std::clamp(num(s) / den(s), 0.0, 0.999) : 0.0;
    const double change = (f - out.trapped).cwiseAbs().maxCoeff();
    out.trapped = f;
    out.iterations += fit_rates(in, out.trapped, X);
    if (change < 1e-9) break;
  }
  out.Q = with_balanced_diagonal(X);
  out.rms_residual = integral_rms(in, out.Q, out.trapped);
  return out;
}

Eigen::MatrixXd solve_master_equation(const Eigen::MatrixXd& Q, const Eigen::VectorXd& e0,
                                      const std::vector<double>& times) {
  Eigen::MatrixXd out(Q.rows(), static_cast<Eigen::Index>(times.size()));
  const size_t T = times.size();
  const double dt = T > 1 ? times[1] - times[0] : 0.0;
  bool uniform = T > 2 && times[0] == 0.0 && dt > 0;
  for (size_t i = 1; uniform && i < T; ++i)
    uniform = std::abs(times[i] - i * dt) <= 1e-12 * times[i];
  if (uniform) {
    const Eigen::MatrixXd Qdt = Q * dt;
    const Eigen::MatrixXd P = Qdt.exp();
    out.col(0) = e0;
    for (size_t i = 1; i < T; ++i)
      out.col(static_cast<Eigen::Index>(i)) = P * out.col(static_cast<Eigen::Index>(i - 1));
    return out;
  }
  for (size_t i = 0; i < T; ++i) {
    const Eigen::MatrixXd Qt = Q * times[i];
    out.col(static_cast<Eigen::Index>(i)) = Qt.exp() * e0;
  }
  return out;
}

Eigen::MatrixXd solve_master_equation_trapped(const Eigen::MatrixXd& Q, const Eigen::VectorXd& f,
                                              const Eigen::VectorXd& e0,
                                              const std::vector<double>& times) {
  const Eigen::VectorXd held = f.cwiseProduct(e0);
  Eigen::MatrixXd out = solve_master_equation(Q, e0 - held, times);
  out.colwise() += held;
  return out;
}

}  // namespace granular
