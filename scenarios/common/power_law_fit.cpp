#include "scenarios/common/power_law_fit.hpp"

#include <cmath>
#include <limits>

namespace granular {

namespace {
// Least squares of log y on u over the points kept by the caller.
PowerLawFit fit_log_y(const std::vector<double>& u, const std::vector<double>& v) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PowerLawFit f;
  f.points = static_cast<int>(u.size());
  f.exponent = f.exponent_stderr = f.prefactor = f.rms_log_residual = nan;
  if (f.points < 2) return f;
  double mu = 0, mv = 0;
  for (size_t i = 0; i < u.size(); ++i) mu += u[i], mv += v[i];
  mu /= f.points, mv /= f.points;
  double suu = 0, suv = 0;
  for (size_t i = 0; i < u.size(); ++i)
    suu += (u[i] - mu) * (u[i] - mu), suv += (u[i] - mu) * (v[i] - mv);
  if (!(suu > 0)) return f;
  f.exponent = suv / suu;
  const double intercept = mv - f.exponent * mu;
  f.prefactor = std::exp(intercept);
  double ss = 0;
  for (size_t i = 0; i < u.size(); ++i) {
    const double r = v[i] - intercept - f.exponent * u[i];
    ss += r * r;
  }
  f.rms_log_residual = std::sqrt(ss / f.points);
  if (f.points > 2) f.exponent_stderr = std::sqrt(ss / (f.points - 2) / suu);
  return f;
}
}  // namespace

PowerLawFit fit_power_law(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<double> u, v;
  for (size_t i = 0; i < x.size() && i < y.size(); ++i)
    if (x[i] > 0 && y[i] > 0 && std::isfinite(x[i]) && std::isfinite(y[i]))
      u.push_back(std::log(x[i])), v.push_back(std::log(y[i]));
  return fit_log_y(u, v);
}

PowerLawFit fit_exponential(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<double> u, v;
  for (size_t i = 0; i < x.size() && i < y.size(); ++i)
    if (y[i] > 0 && std::isfinite(x[i]) && std::isfinite(y[i]))
      u.push_back(x[i]), v.push_back(std::log(y[i]));
  return fit_log_y(u, v);
}

}  // namespace granular
