#include "core/signal/signal_pickers.hpp"

#include <algorithm>
#include <cmath>

namespace granular {

namespace {

// Vertex of the parabola through (i-1, i, i+1): sub-sample time and value of an extremum.
void parabolic_vertex(const Trace& tr, double base, int i, double& t, double& v) {
  const double y0 = tr.a[i - 1] - base, y1 = tr.a[i] - base, y2 = tr.a[i + 1] - base;
  const double den = y0 - 2 * y1 + y2;
  const double s = den != 0.0 ? 0.5 * (y0 - y2) / den : 0.0;  // in samples, |s| <= 1/2
  t = tr.t[i] + s * tr.step();
  v = y1 - 0.25 * (y0 - y2) * s;
}

}  // namespace

Picks pick_travel_times(const Trace& tr, const PickerOptions& o) {
  tr.validate("picker input", 3);
  Picks p;
  int nn = 0;
  double sum = 0;
  for (int i = 0; i < tr.size() && tr.t[i] < o.noise_end; ++i) sum += tr.a[i], ++nn;
  p.baseline = nn > 0 ? sum / nn : 0.0;
  double ss = 0;
  for (int i = 0; i < nn; ++i) ss += (tr.a[i] - p.baseline) * (tr.a[i] - p.baseline);
  p.noise_rms = nn > 0 ? std::sqrt(ss / nn) : 0.0;
  double amax = 0;
  for (int i = 0; i < tr.size(); ++i)
    if (tr.t[i] >= o.search_start) amax = std::max(amax, std::abs(tr.a[i] - p.baseline));
  p.threshold = std::max(o.noise_factor * p.noise_rms, o.relative_threshold * amax);
  if (!(p.threshold > 0)) return p;  // a flat signal: nothing arrives

  const int n = tr.size();
  int first = 0;
  while (first < n && (tr.t[first] < o.search_start || tr.t[first] < o.noise_end)) ++first;
  for (int i = std::max(first, 1); i < n; ++i) {
    const double y = std::abs(tr.a[i] - p.baseline);
    if (y > p.threshold) {
      const double y0 = std::abs(tr.a[i - 1] - p.baseline);
      const double s = y0 < p.threshold ? (p.threshold - y0) / (y - y0) : 0.0;
      p.first_arrival = tr.t[i - 1] + s * (tr.t[i] - tr.t[i - 1]);
      p.arrival_index = i;
      break;
    }
  }
  if (p.arrival_index < 0) return p;
  // The first extremum of each sign beyond the threshold, after the arrival.
  for (int i = std::max(p.arrival_index, 1); i + 1 < n; ++i) {
    const double y = tr.a[i] - p.baseline;
    const bool is_max = tr.a[i] >= tr.a[i - 1] && tr.a[i] > tr.a[i + 1];
    const bool is_min = tr.a[i] <= tr.a[i - 1] && tr.a[i] < tr.a[i + 1];
    if (p.peak_index < 0 && is_max && y > p.threshold) {
      p.peak_index = i;
      parabolic_vertex(tr, p.baseline, i, p.first_peak, p.peak_amplitude);
    }
    if (p.trough_index < 0 && is_min && y < -p.threshold) {
      p.trough_index = i;
      parabolic_vertex(tr, p.baseline, i, p.first_trough, p.trough_amplitude);
    }
    if (p.peak_index >= 0 && p.trough_index >= 0) break;
  }
  return p;
}

}  // namespace granular
