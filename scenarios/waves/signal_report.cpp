#include "scenarios/waves/signal_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/io/dataset_units.hpp"

namespace granular {

SignalSettings read_signal_settings(const SceneFile& sc, const std::string& pre,
                                    double default_noise_end) {
  SignalSettings s;
  const std::string pk = pre + ".picker.", sp = pre + ".spectrum.", rt = pre + ".ratio.";
  s.picker.noise_end = sc.real(pk + "noise_end", default_noise_end);
  s.picker.noise_factor = sc.real(pk + "noise_factor", 5.0);
  s.picker.relative_threshold = sc.real(pk + "relative_threshold", 0.02);
  sc.require(s.picker.noise_factor >= 0, pk + "noise_factor", "must not be negative");
  sc.require(s.picker.relative_threshold >= 0 && s.picker.relative_threshold < 1,
             pk + "relative_threshold", "must lie in [0, 1)");
  const std::string w = sc.text(sp + "window", "lobe");
  try {
    s.spectrum.window = parse_event_window(w, sp + "window");
  } catch (const InputError&) {
    sc.require(false, sp + "window", "must be \"lobe\", \"mirrored\", \"whole\" or \"span\"");
  }
  s.spectrum.taper = sc.real(sp + "taper", 0.0);
  s.spectrum.pad_factor = sc.small_integer(sp + "pad_factor", 8);
  sc.require(s.spectrum.taper >= 0 && s.spectrum.taper <= 1, sp + "taper", "must lie in [0, 1]");
  sc.require(s.spectrum.pad_factor >= 1 && s.spectrum.pad_factor <= 64, sp + "pad_factor",
             "must lie in [1, 64]");
  if (s.spectrum.window == EventWindow::Span) {
    const auto span = sc.reals(sp + "span");
    sc.require(span.size() == 2 && span[1] > span[0], sp + "span",
               "must be [start, end] with end > start (times relative to the first peak)");
    s.span[0] = span[0], s.span[1] = span[1];
  }
  s.band = sc.reals(rt + "band", {});
  sc.require(s.band.empty() || (s.band.size() == 2 && s.band[1] > s.band[0] && s.band[0] >= 0),
             rt + "band", "must be [f_lo, f_hi] with 0 <= f_lo < f_hi");
  s.band_fraction = sc.real(rt + "band_fraction", 0.1);
  sc.require(s.band_fraction > 0 && s.band_fraction < 1, rt + "band_fraction",
             "must lie in (0, 1)");
  s.delay_picker = sc.text(rt + "delay_picker", "first_peak");
  sc.require(s.delay_picker == "first_arrival" || s.delay_picker == "first_peak" ||
                 s.delay_picker == "first_trough",
             rt + "delay_picker", "must be \"first_arrival\", \"first_peak\" or \"first_trough\"");
  return s;
}

double picked_time(const Picks& p, const std::string& which) {
  if (which == "first_arrival") return p.first_arrival;
  if (which == "first_peak") return p.first_peak;
  if (which == "first_trough") return p.first_trough;
  throw InputError("unknown picker " + which);
}

Spectrum analyse_event(const Trace& tr, const Picks& p, const SignalSettings& s, int min_fft) {
  SpectrumOptions o = s.spectrum;
  o.min_fft = std::max(o.min_fft, min_fft);
  if (o.window == EventWindow::Span) {
    if (std::isnan(p.first_peak))
      throw PhysicsError(
          "spectrum: the span window is placed about the first peak, and the"
          " trace has none above its threshold");
    o.span_start = p.first_peak + s.span[0], o.span_end = p.first_peak + s.span[1];
  }
  return event_spectrum(tr, p, o);
}

SpectralRatioFit analyse_ratio(const Trace& t1, const Picks& p1, const Trace& t2, const Picks& p2,
                               const SignalSettings& s, double delay) {
  // Both events on one grid: the longer one's FFT length for both.
  const Spectrum a = analyse_event(t1, p1, s), b = analyse_event(t2, p2, s);
  const int nfft = std::max(a.nfft, b.nfft);
  const Spectrum s1 = analyse_event(t1, p1, s, nfft), s2 = analyse_event(t2, p2, s, nfft);
  if (delay < 0) delay = picked_time(p2, s.delay_picker) - picked_time(p1, s.delay_picker);
  double lo, hi;
  if (s.band.size() == 2)
    lo = s.band[0], hi = s.band[1];
  else
    common_band(s1, s2, s.band_fraction, lo, hi);
  return spectral_ratio(s1, s2, delay, lo, hi);
}

Json picks_json(const Picks& p) {
  Json j = Json::object();
  auto num = [](double v) { return std::isfinite(v) ? Json(v) : Json(); };
  j["first_arrival"] = num(p.first_arrival);
  j["first_peak"] = num(p.first_peak);
  j["first_trough"] = num(p.first_trough);
  j["peak_amplitude"] = num(p.peak_amplitude);
  j["trough_amplitude"] = num(p.trough_amplitude);
  j["baseline"] = p.baseline;
  j["noise_rms"] = p.noise_rms;
  j["threshold"] = p.threshold;
  return j;
}

Json spectrum_json(const Spectrum& s) {
  Json j = Json::object();
  j["window_start"] = s.window_start;
  j["window_end"] = s.window_end;
  j["nfft"] = s.nfft;
  j["df"] = s.df;
  j["dominant_frequency"] = s.dominant_frequency;
  j["energy"] = s.time_energy;
  return j;
}

Json ratio_json(const SpectralRatioFit& r) {
  Json j = Json::object();
  j["band"] = std::vector<double>{r.f_lo, r.f_hi};
  j["points"] = r.points;
  j["delay"] = r.delay;
  j["slope"] = r.slope;
  j["slope_error"] = r.slope_error;
  j["intercept"] = r.intercept;
  j["r2"] = r.r2;
  j["Q"] = std::isfinite(r.q) ? Json(r.q) : Json();
  j["Q_error"] = std::isfinite(r.q_error) ? Json(r.q_error) : Json();
  j["inverse_Q"] = r.inv_q;
  j["inverse_Q_error"] = r.inv_q_error;
  return j;
}

std::string unit_product(const std::vector<std::pair<std::string, int>>& factors) {
  double number = 1;
  std::vector<std::pair<std::string, long>> symbols;  // in the order they first appear
  for (const auto& [unit, power] : factors) {
    std::istringstream in(unit);
    std::string token;
    while (in >> token) {
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end != token.c_str() && *end == '\0') {  // a numeric factor ("1" included)
        number *= std::pow(v, power);
        continue;
      }
      // symbol, then an optional signed power ("mm+2", "us-1"; "mm2" read as "mm+2")
      size_t split = token.find_last_not_of("0123456789") + 1;
      if (split < token.size() && split > 1 && (token[split - 1] == '+' || token[split - 1] == '-'))
        --split;
      const long p = split < token.size() ? std::strtol(token.c_str() + split, nullptr, 10) : 1;
      const std::string symbol = token.substr(0, split);
      auto at = std::find_if(symbols.begin(), symbols.end(),
                             [&](const auto& e) { return e.first == symbol; });
      if (at == symbols.end()) at = symbols.emplace(symbols.end(), symbol, 0);
      at->second += p * power;
    }
  }
  std::ostringstream out;
  out.precision(12);
  if (number != 1) out << number;
  for (const auto& [symbol, p] : symbols) {
    if (p == 0) continue;
    if (out.tellp() > 0) out << ' ';
    out << symbol;
    if (p != 1) out << (p > 0 ? "+" : "") << p;
  }
  return out.tellp() > 0 ? out.str() : "1";
}

std::string frequency_unit(const TraceUnits& u) { return unit_product({{u.time, -1}}); }

std::string energy_unit(const TraceUnits& u) {
  return unit_product({{u.amplitude, 2}, {u.time, 2}});
}

void write_signal(H5Writer& h5, const std::string& g, const Trace& tr, const Picks& p,
                  const Spectrum& s, const TraceUnits& units) {
  write_quantity(h5, g + "/time", tr.t, units.time);
  write_quantity(h5, g + "/amplitude", tr.a, units.amplitude);
  write_quantity(h5, g + "/spectrum/frequency", s.f, frequency_unit(units));
  write_quantity(h5, g + "/spectrum/energy", s.energy, energy_unit(units));
  write_quantity(h5, g + "/spectrum/samples", s.samples, units.amplitude);
  h5.attribute(g + "/spectrum", "window_start", s.window_start);
  h5.attribute(g + "/spectrum", "dominant_frequency", s.dominant_frequency);
  h5.attribute(g, "first_arrival", p.first_arrival);
  h5.attribute(g, "first_peak", p.first_peak);
  h5.attribute(g, "first_trough", p.first_trough);
  h5.attribute(g, "threshold", p.threshold);
  h5.attribute(g, "baseline", p.baseline);
}

}  // namespace granular
