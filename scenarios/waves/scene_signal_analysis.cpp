// Scene `signal_analysis`: travel times (three pickers), first-event spectra and the
// spectral-ratio Q of one or two recorded traces (CSV or HDF5: laboratory transducer
// records or engine output), or, with [synthetic], the validation of the estimators on
// constant-Q wavelets of known Q over noise levels, bands and windows.
#include <algorithm>
#include <cmath>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/signal/synthetic_signals.hpp"
#include "core/signal/trace_io.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"
#include "scenarios/waves/signal_report.hpp"

namespace granular {

namespace {

// An input trace and its units: `<k>.time_unit` and `<k>.amplitude_unit` where the scene
// gives them, else the `unit` attributes of its HDF5 datasets (an engine results.h5 carries
// them), else "1" (numbers in the scene's reduced units, as the shipped example traces,
// which the synthetic scene wrote).
Trace read_input_trace(const SceneFile& s, const std::string& k, TraceUnits& units) {
  units = {"1", "1"};
  const std::string given_time = s.text(k + ".time_unit", ""),
                    given_amplitude = s.text(k + ".amplitude_unit", "");
  const auto apply_given = [&] {
    if (!given_time.empty()) units.time = given_time;
    if (!given_amplitude.empty()) units.amplitude = given_amplitude;
  };
  const std::string file = s.input_path(k + ".file");
  const std::string format = s.text(k + ".format", "csv");
  s.require(format == "csv" || format == "hdf5", k + ".format", "must be \"csv\" or \"hdf5\"");
  try {
    if (format == "csv") {
      const long tc = s.integer(k + ".time_column", 0), ac = s.integer(k + ".amplitude_column", 1);
      s.require(tc >= 0 && ac >= 0 && tc != ac, k + ".amplitude_column",
                "columns must be distinct and non-negative");
      apply_given();
      return read_trace_csv(file, static_cast<int>(tc), static_cast<int>(ac));
    }
    const std::string td = s.text(k + ".time_dataset"), ad = s.text(k + ".amplitude_dataset");
    Trace tr = read_trace_h5(file, td, ad);
    const std::string tu = read_dataset_unit(file, td), au = read_dataset_unit(file, ad);
    if (!tu.empty()) units.time = tu;
    if (!au.empty()) units.amplitude = au;
    apply_given();
    return tr;
  } catch (const InputError& e) {
    s.require(false, k + ".file", e.what());
  }
  return {};
}

struct Synthetic {
  double q = 20, fp = 1, t1 = 5, t2 = 15, dt = 0.01, source_time = 2;
  int samples = 4096, seeds = 10;
  std::vector<double> noise, fractions;
};

Synthetic read_synthetic(const SceneFile& s) {
  Synthetic y;
  y.q = s.real("synthetic.q");
  y.fp = s.real("synthetic.peak_frequency");
  const auto tt = s.reals("synthetic.travel_times");
  s.require(tt.size() == 2 && tt[1] > tt[0] && tt[0] >= 0, "synthetic.travel_times",
            "must be [t1, t2] with t2 > t1 >= 0");
  y.t1 = tt[0], y.t2 = tt[1];
  y.dt = s.real("synthetic.dt");
  y.samples = s.small_integer("synthetic.samples");
  y.source_time = s.real("synthetic.source_time");
  y.seeds = s.small_integer("synthetic.seeds", 10);
  y.noise = s.reals("synthetic.noise");
  y.fractions = s.reals("synthetic.band_fractions");
  s.require(y.q > 0, "synthetic.q", "must be positive");
  s.require(y.fp > 0, "synthetic.peak_frequency", "must be positive");
  s.require(y.dt > 0 && y.dt < 0.1 / y.fp, "synthetic.dt", "must lie in (0, 0.1/peak_frequency)");
  s.require(y.samples >= 64, "synthetic.samples", "must be at least 64");
  s.require(y.t2 + y.source_time + 4 / y.fp < y.samples * y.dt, "synthetic.samples",
            "must cover the later pulse (t2 + source_time + 4/peak_frequency)");
  s.require(y.seeds >= 2, "synthetic.seeds", "must be at least 2");
  for (double v : y.noise) s.require(v >= 0, "synthetic.noise", "levels must not be negative");
  for (double v : y.fractions)
    s.require(v > 0 && v < 1, "synthetic.band_fractions", "must lie in (0, 1)");
  s.require(!y.noise.empty() && !y.fractions.empty(), "synthetic.noise",
            "and synthetic.band_fractions need at least one value each");
  return y;
}

// The scene's setup: the analysis settings and either the synthetic validation or the
// recorded traces (one or two) with their units.
struct SignalSetup {
  bool synthetic = false;
  SignalSettings settings;
  Synthetic syn;
  Trace tr[2];
  TraceUnits units[2];
  int count = 0;
  double delay = -1;  // the ratio's delay; -1: the difference of the picked times
};

SignalSetup read_setup(const SceneFile& scene) {
  SignalSetup c;
  c.synthetic = scene.has("synthetic");
  c.settings = read_signal_settings(scene, "analysis", 0.0);
  if (c.synthetic) {
    c.syn = read_synthetic(scene);
    if (!scene.has("analysis.picker.noise_end"))
      c.settings.picker.noise_end = c.syn.source_time / 2;
  } else {
    c.tr[0] = read_input_trace(scene, "trace1", c.units[0]);
    c.count = 1;
    if (scene.has("trace2")) c.tr[1] = read_input_trace(scene, "trace2", c.units[1]), c.count = 2;
    c.delay = scene.real("analysis.ratio.delay", -1.0);
    scene.require(c.delay == -1.0 || c.delay > 0, "analysis.ratio.delay",
                  "must be positive (absent: the difference of the picked times)");
  }
  scene.reject_unknown_keys();
  return c;
}

const std::vector<EventWindow> kWindows = {EventWindow::Whole, EventWindow::Span, EventWindow::Lobe,
                                           EventWindow::Mirrored};

// One cell of the estimator table: the error of 1/Q over the seeds' noise draws.
struct EstimatorCell {
  size_t window = 0;  // index into kWindows
  double fraction = 0, noise = 0;
  int runs = 0;                            // draws the estimator got through
  double mean = NAN, sd = NAN, fit = NAN;  // relative errors of 1/Q, and of its fit
};

EstimatorCell estimate(const Synthetic& y, const SignalSettings& base, const Trace& c1,
                       const Trace& c2, size_t w, double frac, double sigma) {
  SignalSettings s = base;
  s.spectrum.window = kWindows[w];
  s.span[0] = -4 / y.fp, s.span[1] = 4 / y.fp;
  s.band.clear();
  s.band_fraction = frac;
  double sum = 0, sum2 = 0, fit_err = 0;
  int ok = 0;
  for (int seed = 0; seed < y.seeds; ++seed) {
    Trace r1 = c1, r2 = c2;
    add_noise(r1, sigma, 1000 + seed), add_noise(r2, sigma, 2000 + seed);
    try {
      const Picks p1 = pick_travel_times(r1, s.picker), p2 = pick_travel_times(r2, s.picker);
      // The true delay: the estimator is judged, not the pickers.
      const SpectralRatioFit f = analyse_ratio(r1, p1, r2, p2, s, y.t2 - y.t1);
      const double e = f.inv_q * y.q - 1;  // relative error of 1/Q
      sum += e, sum2 += e * e, fit_err += f.inv_q_error * y.q, ++ok;
    } catch (const std::exception&) {  // no arrival or too few bins: counted as failed
    }
  }
  EstimatorCell cell;
  cell.window = w, cell.fraction = frac, cell.noise = sigma, cell.runs = ok;
  const double mean = ok > 0 ? sum / ok : NAN;
  cell.mean = mean;
  cell.sd = ok > 1 ? std::sqrt(std::max(0.0, (sum2 - ok * mean * mean) / (ok - 1))) : NAN;
  cell.fit = ok > 0 ? fit_err / ok : NAN;
  return cell;
}

// The synthetic validation as data: the noisy example pair, the estimator table and the
// noise-free pair's fit.
struct SyntheticResult {
  Trace example[2];
  std::vector<EstimatorCell> cells;
  SpectralRatioFit noise_free;
  // What stopped the noise-free fit, raised once the example traces are written: a run that
  // fails there still leaves them to look at.
  std::exception_ptr stopped;
};

// Estimator error over noise levels x band fractions x windows, `seeds` noise draws each.
SyntheticResult validate_estimators(const Synthetic& y, const SignalSettings& base) {
  Trace src;
  src.t.resize(y.samples), src.a.resize(y.samples);
  for (int i = 0; i < y.samples; ++i)
    src.t[i] = i * y.dt, src.a[i] = ricker(i * y.dt, y.fp, y.source_time);
  const Trace c1 = constant_q_propagate(src, y.t1, y.q, y.fp);
  const Trace c2 = constant_q_propagate(src, y.t2, y.q, y.fp);
  SyntheticResult r;
  // example traces for the laboratory-style run of this scene (noise: the first level)
  r.example[0] = c1, r.example[1] = c2;
  add_noise(r.example[0], y.noise.front(), 1), add_noise(r.example[1], y.noise.front(), 2);
  for (size_t w = 0; w < kWindows.size(); ++w)
    for (double frac : y.fractions)
      for (double sigma : y.noise) r.cells.push_back(estimate(y, base, c1, c2, w, frac, sigma));
  try {  // the noise-free pair through the full analysis of this scene's settings
    const Picks p1 = pick_travel_times(c1, base.picker), p2 = pick_travel_times(c2, base.picker);
    r.noise_free = analyse_ratio(c1, p1, c2, p2, base, y.t2 - y.t1);
  } catch (...) {
    r.stopped = std::current_exception();
  }
  return r;
}

// The example traces as CSV files beside results.h5.
void write_example_traces(const std::string& dir, const SyntheticResult& r) {
  for (int k = 0; k < 2; ++k) {
    const Trace& tr = r.example[k];
    std::ostringstream csv;
    csv.precision(12);
    csv << "time,amplitude\n";
    for (int i = 0; i < tr.size(); ++i) csv << tr.t[i] << "," << tr.a[i] << "\n";
    write_text_file(dir + "/trace" + std::to_string(k + 1) + ".csv", csv.str());
  }
}

// The example traces, the estimator table (results.h5 and the summary) and the noise-free fit.
void write_synthetic(SceneOutput& output, const std::string& dir, const Synthetic& y,
                     const SyntheticResult& r) {
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  write_example_traces(dir, r);
  Json out = Json::object(), table = Json::array();
  std::vector<double> col_noise, col_fraction, col_window, col_mean, col_sd, col_fit_err;
  for (const EstimatorCell& c : r.cells) {
    Json j = Json::object();
    j["window"] = event_window_name(kWindows[c.window]);
    j["band_fraction"] = c.fraction;
    j["noise"] = c.noise;
    j["runs"] = c.runs;
    j["mean_relative_error_inverse_Q"] = std::isfinite(c.mean) ? Json(c.mean) : Json();
    j["sd_relative_error_inverse_Q"] = std::isfinite(c.sd) ? Json(c.sd) : Json();
    j["mean_fit_error_relative"] = c.runs > 0 ? Json(c.fit) : Json();
    table.push(j);
    col_noise.push_back(c.noise), col_fraction.push_back(c.fraction);
    col_window.push_back(static_cast<double>(c.window));
    col_mean.push_back(c.mean), col_sd.push_back(c.sd), col_fit_err.push_back(c.fit);
  }
  out["estimator_error"] = table;
  // Reduced units: the noise is in units of the Ricker source's peak amplitude (1); the
  // errors are relative to 1/Q; window is an index into the `windows` attribute.
  write_quantity(h5, "/estimator/noise", col_noise, "1");
  write_quantity(h5, "/estimator/band_fraction", col_fraction, "1");
  write_quantity(h5, "/estimator/window", col_window, "1");
  write_quantity(h5, "/estimator/mean_relative_error", col_mean, "1");
  write_quantity(h5, "/estimator/sd_relative_error", col_sd, "1");
  write_quantity(h5, "/estimator/fit_error", col_fit_err, "1");
  h5.attribute("/estimator", "windows", "whole,span,lobe,mirrored");
  h5.attribute("/estimator", "q", y.q);
  if (r.stopped) std::rethrow_exception(r.stopped);
  out["noise_free_fit"] = ratio_json(r.noise_free);
  out["q_true"] = y.q;
  summary["synthetic"] = out;
}

// The recorded traces as data: picks and spectra (one frequency grid for both), and the
// spectral ratio of a pair.
struct TracesResult {
  int count = 0;
  Picks p[2];
  Spectrum s[2];
  SpectralRatioFit ratio;  // with two traces
};

// A pair's ratio needs trace2 to be the farther receiver: a picked delay that is not positive
// means the files are swapped, or the picker caught noise.
void require_farther_second(const SceneFile& scene, const SignalSettings& settings,
                            const Picks p[2]) {
  const double picked =
      picked_time(p[1], settings.delay_picker) - picked_time(p[0], settings.delay_picker);
  std::ostringstream why;
  why << "the " << settings.delay_picker << " of trace2 comes " << picked
      << " after that of trace1, which is not positive: trace2.file must hold the"
      << " farther receiver, or set analysis.ratio.delay";
  scene.require(picked > 0, "trace2.file", why.str());
}

TracesResult analyse_traces(const SceneFile& scene, const SignalSetup& c) {
  TracesResult r;
  r.count = c.count;
  int nfft = 0;
  for (int k = 0; k < c.count; ++k) {
    r.p[k] = pick_travel_times(c.tr[k], c.settings.picker);
    r.s[k] = analyse_event(c.tr[k], r.p[k], c.settings);
    nfft = std::max(nfft, r.s[k].nfft);
  }
  for (int k = 0; k < c.count; ++k) {
    r.s[k] = analyse_event(c.tr[k], r.p[k], c.settings, nfft);  // one grid for both
    std::cout << "trace" << k + 1 << ": first arrival " << r.p[k].first_arrival << ", first peak "
              << r.p[k].first_peak << ", first trough " << r.p[k].first_trough
              << ", dominant frequency " << r.s[k].dominant_frequency << "\n";
  }
  if (c.count == 2) {
    if (c.delay < 0) require_farther_second(scene, c.settings, r.p);
    r.ratio = analyse_ratio(c.tr[0], r.p[0], c.tr[1], r.p[1], c.settings, c.delay);
    const SpectralRatioFit& f = r.ratio;
    std::cout << "spectral ratio: Q = " << f.q << " +- " << f.q_error << " (1/Q = " << f.inv_q
              << " +- " << f.inv_q_error << ") over [" << f.f_lo << ", " << f.f_hi << "]\n";
  }
  return r;
}

// Each trace (results.h5 and the summary), the travel-time differences and the ratio.
void write_traces(SceneOutput& output, const SignalSetup& c, const TracesResult& r) {
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  Json traces = Json::object();
  for (int k = 0; k < r.count; ++k) {
    const std::string name = "trace" + std::to_string(k + 1);
    Json j = Json::object();
    j["picks"] = picks_json(r.p[k]);
    j["spectrum"] = spectrum_json(r.s[k]);
    traces[name] = j;
    write_signal(h5, "/" + name, c.tr[k], r.p[k], r.s[k], c.units[k]);
  }
  summary["traces"] = traces;
  if (r.count != 2) return;
  Json tt = Json::object();
  for (const char* w : {"first_arrival", "first_peak", "first_trough"})
    tt[w] = std::isfinite(picked_time(r.p[1], w) - picked_time(r.p[0], w))
                ? Json(picked_time(r.p[1], w) - picked_time(r.p[0], w))
                : Json();
  summary["travel_time_differences"] = tt;
  const SpectralRatioFit& f = r.ratio;
  summary["spectral_ratio"] = ratio_json(f);
  // both spectra on trace1's frequency grid, in its time unit
  write_quantity(h5, "/ratio/frequency", f.f, frequency_unit(c.units[0]));
  write_quantity(h5, "/ratio/log_ratio", f.log_ratio, "1");  // ln(A2/A1)
  h5.attribute("/ratio", "slope", f.slope);
  h5.attribute("/ratio", "intercept", f.intercept);
  h5.attribute("/ratio", "Q", f.q);
}

}  // namespace

void run_signal_analysis(const SceneFile& scene, const RunOptions& opts) {
  const SignalSetup c = read_setup(scene);
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "signal_analysis");
  if (c.synthetic)
    write_synthetic(output, opts.out_dir, c.syn, validate_estimators(c.syn, c.settings));
  else
    write_traces(output, c, analyse_traces(scene, c));
  output.h5().attribute("/", "synthetic", c.synthetic ? 1.0 : 0.0);
  output.finish();
}

}  // namespace granular
