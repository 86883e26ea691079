#include "core/signal/spectral_ratio.hpp"

#include <algorithm>
#include <cmath>

#include "core/run/error.hpp"

namespace granular {

SpectralRatioFit spectral_ratio(const Spectrum& s1, const Spectrum& s2, double delay, double f_lo,
                                double f_hi) {
  if (s1.nfft != s2.nfft || std::abs(s1.df - s2.df) > 1e-9 * s1.df)
    throw InputError(
        "spectral ratio: the two spectra have different frequency grids (pad both"
        " to the same FFT length)");
  if (!(delay > 0)) throw InputError("spectral ratio: the travel-time difference must be positive");
  if (!(f_hi > f_lo))
    throw InputError("spectral ratio: the band's upper end must exceed its lower");
  SpectralRatioFit r;
  r.f_lo = f_lo, r.f_hi = f_hi, r.delay = delay;
  for (size_t k = 1; k < s1.f.size(); ++k) {
    if (s1.f[k] < f_lo || s1.f[k] > f_hi) continue;
    if (!(s1.amplitude[k] > 0) || !(s2.amplitude[k] > 0)) continue;
    r.f.push_back(s1.f[k]);
    r.log_ratio.push_back(std::log(s2.amplitude[k] / s1.amplitude[k]));
  }
  const int n = static_cast<int>(r.f.size());
  r.points = n;
  if (n < 3)
    throw InputError("spectral ratio: the band [" + std::to_string(f_lo) + ", " +
                     std::to_string(f_hi) + "] holds " + std::to_string(n) +
                     " usable frequencies; at least 3 are needed (widen it or pad the FFT)");
  double fm = 0, ym = 0;
  for (int i = 0; i < n; ++i) fm += r.f[i] / n, ym += r.log_ratio[i] / n;
  double sff = 0, sfy = 0, syy = 0;
  for (int i = 0; i < n; ++i) {
    sff += (r.f[i] - fm) * (r.f[i] - fm);
    sfy += (r.f[i] - fm) * (r.log_ratio[i] - ym);
    syy += (r.log_ratio[i] - ym) * (r.log_ratio[i] - ym);
  }
  r.slope = sfy / sff;
  r.intercept = ym - r.slope * fm;
  double rss = 0;
  for (int i = 0; i < n; ++i) {
    const double e = r.log_ratio[i] - r.intercept - r.slope * r.f[i];
    rss += e * e;
  }
  r.slope_error = std::sqrt(rss / (n - 2) / sff);
  r.r2 = syy > 0 ? 1 - rss / syy : 1.0;
  r.inv_q = -r.slope / (M_PI * delay);
  r.inv_q_error = r.slope_error / (M_PI * delay);
  r.q = r.inv_q != 0 ? 1.0 / r.inv_q : INFINITY;
  r.q_error = r.q * r.q * r.inv_q_error;
  return r;
}

void common_band(const Spectrum& s1, const Spectrum& s2, double fraction, double& f_lo,
                 double& f_hi) {
  const double m1 = *std::max_element(s1.amplitude.begin(), s1.amplitude.end());
  const double m2 = *std::max_element(s2.amplitude.begin(), s2.amplitude.end());
  const size_t nb = std::min(s1.f.size(), s2.f.size());
  auto inside = [&](size_t k) {
    return s1.amplitude[k] > fraction * m1 && s2.amplitude[k] > fraction * m2;
  };
  // Grow the band both ways from the first spectrum's largest amplitude at f > 0.
  size_t kc = 1;
  for (size_t k = 2; k < nb; ++k)
    if (s1.amplitude[k] > s1.amplitude[kc]) kc = k;
  size_t lo = kc, hi = kc;
  while (lo > 1 && inside(lo - 1)) --lo;
  while (hi + 1 < nb && inside(hi + 1)) ++hi;
  f_lo = s1.f[lo];
  f_hi = s1.f[hi];
}

}  // namespace granular
