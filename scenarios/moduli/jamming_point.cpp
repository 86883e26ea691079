// Jamming density from the decompression series (see jamming_point.hpp).
#include "scenarios/moduli/jamming_point.hpp"

#include <cmath>
#include <limits>
#include <set>

namespace granular {

std::vector<JammingPoint> jamming_points(const std::map<std::string, std::vector<double>>& prep,
                                         const std::string& pressure_key, double alpha,
                                         double p_max) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<JammingPoint> out;
  for (const char* k : {"phi", "z_corrected", "direction", "variant"})
    if (!prep.count(k)) return out;
  if (!prep.count(pressure_key)) return out;
  const auto& phi = prep.at("phi");
  const auto& z = prep.at("z_corrected");
  const auto& dir = prep.at("direction");
  const auto& var = prep.at("variant");
  const auto& p = prep.at(pressure_key);
  std::set<int> variants;
  for (double v : var) variants.insert(static_cast<int>(v));
  for (int v : variants) {
    JammingPoint j;
    j.variant = v;
    j.phi_lowest_jammed = j.phi_highest_unjammed = nan;
    // Least squares of y = a + b phi with y = P^(1/alpha).
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    std::vector<std::pair<double, double>> pts;
    for (size_t i = 0; i < phi.size(); ++i) {
      if (static_cast<int>(var[i]) != v || dir[i] >= 0) continue;
      // fmin/fmax ignore the NaN they start from.
      if (z[i] > 0)
        j.phi_lowest_jammed = std::fmin(j.phi_lowest_jammed, phi[i]);
      else
        j.phi_highest_unjammed = std::fmax(j.phi_highest_unjammed, phi[i]);
      if (z[i] > 0 && p[i] > 0 && p[i] <= p_max) {
        const double y = std::pow(p[i], 1.0 / alpha);
        pts.push_back({phi[i], y});
        n += 1, sx += phi[i], sy += y, sxx += phi[i] * phi[i], sxy += phi[i] * y;
      }
    }
    j.points = static_cast<int>(n);
    j.phi_j = j.phi_j_stderr = nan;
    const double det = n * sxx - sx * sx;
    if (n >= 4 && det > 0) {
      const double b = (n * sxy - sx * sy) / det, a = (sy - b * sx) / n;
      double ss = 0;
      for (const auto& [x, y] : pts) ss += (y - a - b * x) * (y - a - b * x);
      const double s2 = ss / (n - 2);
      // phi_J = -a/b; its variance from those of a and b and their covariance.
      const double va = s2 * sxx / det, vb = s2 * n / det, cab = -s2 * sx / det;
      if (b > 0) {
        j.phi_j = -a / b;
        const double ga = -1 / b, gb = a / (b * b);
        j.phi_j_stderr = std::sqrt(std::fmax(0.0, ga * ga * va + gb * gb * vb + 2 * ga * gb * cab));
      }
    }
    out.push_back(j);
  }
  return out;
}

}  // namespace granular
