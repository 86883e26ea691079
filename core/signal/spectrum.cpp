#include "core/signal/spectrum.hpp"

#include <algorithm>
#include <cmath>

#include "core/run/error.hpp"
#include "core/signal/real_fft.hpp"

namespace granular {

namespace {

// Index of the last sample at or before i where a - base changes sign (the onset of the
// lobe containing i), and of the first sample after i where it does (its end).
int lobe_start(const Trace& tr, double base, int i) {
  const bool pos = tr.a[i] - base > 0;
  while (i > 0 && ((tr.a[i - 1] - base > 0) == pos) && tr.a[i - 1] != base) --i;
  return i > 0 ? i - 1 : 0;  // keep the last sample of the other sign (or zero): the crossing
}
int lobe_end(const Trace& tr, double base, int i) {
  const bool pos = tr.a[i] - base > 0;
  const int n = tr.size();
  while (i + 1 < n && ((tr.a[i + 1] - base > 0) == pos) && tr.a[i + 1] != base) ++i;
  return i + 1 < n ? i + 1 : n - 1;
}

}  // namespace

EventWindow parse_event_window(const std::string& name, const std::string& key) {
  if (name == "whole") return EventWindow::Whole;
  if (name == "span") return EventWindow::Span;
  if (name == "lobe") return EventWindow::Lobe;
  if (name == "mirrored") return EventWindow::Mirrored;
  throw InputError(key + " = \"" + name +
                   "\" is not a window: use \"whole\", \"span\", \"lobe\" or \"mirrored\"");
}

const char* event_window_name(EventWindow w) {
  switch (w) {
    case EventWindow::Whole:
      return "whole";
    case EventWindow::Span:
      return "span";
    case EventWindow::Lobe:
      return "lobe";
    case EventWindow::Mirrored:
      return "mirrored";
  }
  return "?";
}

int next_power_of_two(int n) {
  int p = 1;
  while (p < n) p *= 2;
  return p;
}

Spectrum energy_spectrum(const std::vector<double>& samples, double dt, int nfft) {
  if (nfft < static_cast<int>(samples.size()) || nfft < 2)
    throw InputError("spectrum: FFT length " + std::to_string(nfft) + " is shorter than the " +
                     std::to_string(samples.size()) + " samples");
  RealFft fft(nfft);
  std::fill(fft.in(), fft.in() + nfft, 0.0);
  std::copy(samples.begin(), samples.end(), fft.in());
  fft.forward();
  Spectrum s;
  s.dt = dt, s.nfft = nfft, s.df = 1.0 / (nfft * dt);
  s.samples = samples;
  for (double v : samples) s.time_energy += v * v * dt;
  const int nb = nfft / 2 + 1;
  s.f.resize(nb), s.amplitude.resize(nb), s.energy.resize(nb);
  for (int k = 0; k < nb; ++k) {
    const double re = dt * fft.out()[k][0], im = dt * fft.out()[k][1];
    s.f[k] = k * s.df;
    s.energy[k] = re * re + im * im;
    s.amplitude[k] = std::sqrt(s.energy[k]);
  }
  s.dominant_frequency = dominant_frequency(s, &s.dominant_energy);
  return s;
}

double spectral_energy(const Spectrum& s) {
  const int nb = static_cast<int>(s.energy.size());
  double sum = s.energy[0];
  for (int k = 1; k < nb; ++k) sum += (s.nfft % 2 == 0 && k == nb - 1 ? 1.0 : 2.0) * s.energy[k];
  return sum * s.df;
}

double dominant_frequency(const Spectrum& s, double* energy) {
  const int nb = static_cast<int>(s.energy.size());
  int kmax = 1;
  for (int k = 2; k + 1 < nb; ++k)
    if (s.energy[k] > s.energy[kmax]) kmax = k;
  if (nb < 3 || s.energy[kmax] <= s.energy[kmax - 1] || s.energy[kmax] < s.energy[kmax + 1]) {
    if (energy) *energy = s.energy[0];
    return 0.0;
  }
  const double y0 = s.energy[kmax - 1], y1 = s.energy[kmax], y2 = s.energy[kmax + 1];
  const double den = y0 - 2 * y1 + y2;
  const double d = den != 0 ? 0.5 * (y0 - y2) / den : 0.0;
  if (energy) *energy = y1 - 0.25 * (y0 - y2) * d;
  return (kmax + d) * s.df;
}

Spectrum event_spectrum(const Trace& tr, const Picks& p, const SpectrumOptions& o) {
  tr.validate("spectrum input");
  const int n = tr.size();
  const double base = p.baseline;
  int i0 = 0, i1 = n - 1;
  std::vector<double> w;
  if (o.window == EventWindow::Span) {
    if (!(o.span_end > o.span_start))
      throw InputError("spectrum: the span's end must follow its start");
    while (i0 < n && tr.t[i0] < o.span_start) ++i0;
    while (i1 >= 0 && tr.t[i1] > o.span_end) --i1;
    if (i1 - i0 < 2) throw InputError("spectrum: the span holds fewer than three samples");
  } else if (o.window == EventWindow::Lobe || o.window == EventWindow::Mirrored) {
    if (p.arrival_index < 0)
      throw PhysicsError("spectrum: no arrival was picked, so there is no first event");
    i0 = lobe_start(tr, base, p.arrival_index);
    i1 = lobe_end(tr, base, p.arrival_index);
    if (o.window == EventWindow::Mirrored) {
      // Up to the picked first peak (trough) of a positive (negative) lobe: a local scan
      // for the extremum would stop at the first wiggle of a noisy rise.
      const bool positive = tr.a[p.arrival_index] - base > 0;
      int ie = positive ? p.peak_index : p.trough_index;
      if (ie < i0 || ie > i1) {  // no picked extremum inside the lobe: its largest sample
        ie = i0;
        for (int i = i0; i <= i1; ++i)
          if (std::abs(tr.a[i] - base) > std::abs(tr.a[ie] - base)) ie = i;
      }
      i1 = ie;
    }
  }
  for (int i = i0; i <= i1; ++i) w.push_back(tr.a[i] - base);
  if (o.window == EventWindow::Mirrored) {
    // quarter -> half period (mirror in time about the extremum) -> full (opposite sign)
    const int q = static_cast<int>(w.size());
    for (int i = q - 2; i >= 0; --i) w.push_back(w[i]);
    const int h = static_cast<int>(w.size());
    for (int i = 1; i < h; ++i) w.push_back(-w[i]);
  }
  if (o.taper > 0) {  // Tukey: cosine ramps over taper/2 of the window at each end
    const int m = static_cast<int>(w.size());
    const double r = std::min(o.taper, 1.0) * (m - 1) / 2.0;
    for (int i = 0; i < m; ++i) {
      const double x = std::min<double>(i, m - 1 - i);
      if (x < r) w[i] *= 0.5 * (1 - std::cos(M_PI * x / r));
    }
  }
  const int nfft = next_power_of_two(std::max<int>(o.pad_factor * w.size(), o.min_fft));
  Spectrum s = energy_spectrum(w, tr.step(), nfft);
  s.window_start = tr.t[i0];
  s.window_end = tr.t[i0] + (w.size() - 1) * tr.step();
  return s;
}

}  // namespace granular
