// Scene `chain_tones`: standing-wave tones on disordered chains, looked at the ways the source
// study shows them (docs/model_chains.md §3-5): space-time maps of one realization's
// displacement u_p(t), bead energy TE_p(t) and spectral energy TE^(k)(t); band-energy curves
// of one realization against the ensemble, of the agitated band against the disorder and of
// several bands at one disorder; what each master-equation fitting procedure sees (decay of
// the agitated band, rise of its neighbour, with both fits over their windows); and the check
// that two amplitudes u0 differ only in amplitude (the linear regime).
// Tones are given as wavenumbers N (u_i = u0 sin(N 2 pi i / L)): the source's N = 4r, band
// centres (wave.bands), or N = 1 for the fundamental.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>

#include "core/chain/chain_spectrum.hpp"
#include "core/chain/master_equation.hpp"
#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/progress.hpp"
#include "kernels/chain/chain_energy.hpp"
#include "scenarios/chains/chain_config.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

using Space = Kokkos::DefaultExecutionSpace;

// One experiment: R realizations from one tone at one amplitude. Series are (rows x T),
// row-major, T = samples + 1.
struct ToneRun {
  int tone = 0;
  double u0 = 0;
  std::vector<double> bands_mean;     // ensemble-mean normalized band energies (B x T)
  std::vector<double> bands_one;      // the mapped realization's (B x T)
  std::vector<double> spectrum_one;   // its TE^(k) / its total energy (bins x T)
  std::vector<double> u_one, te_one;  // its displacement and bead energy maps (N x T)
  std::vector<double> total_mean;     // ensemble-mean total energy (T)
};

// The scene's keys, read and checked.
struct TonesSetup {
  ChainScene cs;
  int B = 0, L = 0;  // bands, sites
  long samples = 0, per_sample = 0;
  std::vector<int> tones;  // distinct, as listed (wave.tones, then the centres of wave.bands)
  std::vector<double> amplitudes;
  int mapped = 0;            // the realization whose maps are kept
  int ftone = 0;             // the tone whose band's decay and neighbour's rise are fitted
  int fband = 0, nband = 0;  // its band and the neighbour whose rise is fitted
  FitWindow fw1, fw2;        // procedures 1 and 2
};

// The fits are drawn for this tone (fit.tone; default: the lowest tone above the fundamental
// band), its band and the neighbour whose rise is fitted.
void choose_fit_tone(TonesSetup& s, double fit_tone) {
  const int L = s.L, B = s.B;
  s.ftone = fit_tone > 0 ? static_cast<int>(fit_tone) : s.tones.back();
  if (fit_tone <= 0)
    for (int t : s.tones)
      if (chain_band_of_bin(t, L, B) > 0) {
        s.ftone = t;
        break;
      }
  s.fband = chain_band_of_bin(s.ftone, L, B);
  s.nband = s.fband + 1 < B ? s.fband + 1 : s.fband - 1;
}

TonesSetup read_setup(const SceneFile& scene) {
  TonesSetup s;
  ChainScene& cs = s.cs;
  cs = read_chain_scene(scene);
  const int B = s.B = scene.small_integer("bands.count");
  const long samples = s.samples = scene.small_integer("time.samples");
  std::vector<double> tone_list = scene.reals("wave.tones", {});
  const std::vector<double> centre_bands = scene.reals("wave.bands", {});
  s.amplitudes = scene.reals("wave.u0", {0.01, 0.001});
  s.mapped = scene.small_integer("maps.realization", 0);
  const double fit_tone = scene.real("fit.tone", -1);
  const auto w1 = scene.reals("fit.window_nonlinear", {2, 18});
  const auto w2 = scene.reals("fit.window_linear", {2, 8});
  const int L = s.L = cs.spec.sites();
  scene.require(!cs.exact, "time.solver", "must be \"verlet\" here");
  scene.require(cs.spec.boundary == ChainBoundary::Fixed || L % 2 == 0, "chain.beads",
                "must be even for a periodic ring");
  scene.require(B >= 2 && B <= L / 2, "bands.count",
                "must be between 2 and L/2 = " + std::to_string(L / 2));
  scene.require(samples >= 3, "time.samples", "must be at least 3");
  for (double b : centre_bands) {
    scene.require(b >= 0 && b < B && b == std::floor(b), "wave.bands",
                  "must be band indices in [0, bands.count)");
    tone_list.push_back(chain_band_tone(static_cast<int>(b), L, B));
  }
  scene.require(!tone_list.empty(), "wave.tones", "give wave.tones and/or wave.bands");
  std::vector<int>& tones = s.tones;
  for (double t : tone_list) {
    scene.require(t >= 1 && t <= L / 2 && t == std::floor(t), "wave.tones",
                  "must be whole wavenumbers in [1, L/2 = " + std::to_string(L / 2) + "]");
    if (std::find(tones.begin(), tones.end(), static_cast<int>(t)) == tones.end())
      tones.push_back(static_cast<int>(t));
  }
  scene.require(!s.amplitudes.empty(), "wave.u0", "must list at least one amplitude");
  scene.require_distinct("wave.u0", s.amplitudes);
  for (double a : s.amplitudes)
    scene.require(a > 0 && a < 0.1, "wave.u0", "must be in (0, 0.1): small against the overlap");
  scene.require(s.mapped >= 0 && s.mapped < cs.realizations, "maps.realization",
                "must be a realization index below disorder.realizations");
  scene.require(fit_tone < 0 || std::find(tones.begin(), tones.end(), int(fit_tone)) != tones.end(),
                "fit.tone", "must be one of the tones");
  auto window = [&](const std::vector<double>& w, const char* key) {
    scene.require(w.size() == 2 && w[0] >= 0 && w[1] > w[0] + 1 && w[1] <= samples, key,
                  "must be [first, last] sample indices within time.samples");
    return FitWindow{static_cast<int>(w[0]), static_cast<int>(w[1])};
  };
  s.fw1 = window(w1, "fit.window_nonlinear"), s.fw2 = window(w2, "fit.window_linear");
  scene.require_memory("time.samples", 8.0 * (samples + 1) * (2.0 * B + 3.0 * L) * tones.size() *
                                           s.amplitudes.size() * cs.xis.size());
  s.per_sample = chain_steps_per_sample(scene, cs);
  scene.reject_unknown_keys();
  choose_fit_tone(s, fit_tone);
  return s;
}

// What the fitting procedures see at one disorder (first amplitude of the fitted tone): the
// decay of the agitated band and the rise of its neighbour, with procedure 1 (exponential,
// long window) and 2 (straight lines through the origin, short window).
struct ToneFits {
  std::vector<double> decay, rise;  // normalized band energies (T)
  ExpFit d1, r1;                    // (1 - y1) e^{-z1 t} + y1 and y2 (1 - e^{-z2 t})
  double x1 = 0, x2 = 0;            // slopes of 1 - e_s and e_r
};

// One amplitude against the first at one tone: the linear regime's check.
struct AmplitudeCheck {
  int tone = 0;
  double u0_first = 0, u0 = 0;
  double band_difference = 0;  // largest |difference| of normalized band energies
  double u_difference = 0;     // largest |difference| of u/u0 maps, relative to the largest
  double energy_ratio = 0;     // the energy ratio over (u0 ratio)^2
};

// Everything one disorder's ensemble gives, as written to /xi_<k> and summary.json.
struct TonesAtXi {
  double xi = 0;
  std::vector<double> times;
  std::vector<ToneRun> runs;  // tone-major, then amplitude
  std::vector<AmplitudeCheck> checks;
  ToneFits fits;
};

// Every experiment of the scene, its series zeroed (tone-major, then amplitude).
std::vector<ToneRun> empty_runs(const TonesSetup& s, long T) {
  const int B = s.B, N = s.cs.spec.beads;
  std::vector<ToneRun> runs;
  for (int t : s.tones)
    for (double a : s.amplitudes) {
      ToneRun run;
      run.tone = t, run.u0 = a;
      run.bands_mean.assign(B * T, 0.0), run.bands_one.assign(B * T, 0.0);
      run.u_one.assign(N * T, 0.0), run.te_one.assign(N * T, 0.0);
      run.total_mean.assign(T, 0.0);
      runs.push_back(std::move(run));
    }
  return runs;
}

// Sample s of every row (R rows per experiment): the ensemble means, and the mapped
// realization's band energies, spectrum, displacement and bead energies.
template <class HostField>
void record_sample(std::vector<ToneRun>& runs, const TonesSetup& s, long sample,
                   const std::vector<double>& e, const ChainSpectrum& spectrum, const HostField& hu,
                   const HostField& hte, int rows) {
  const int R = s.cs.realizations, N = s.cs.spec.beads, B = s.B;
  const int bins = spectrum.lattice().bins();
  const long T = s.samples + 1;
  for (int row = 0; row < rows; ++row) {
    ToneRun& run = runs[row / R];
    const int r = row % R;
    double total = 0;
    for (int q = 0; q < B; ++q) total += e[row * B + q];
    for (int q = 0; q < B; ++q) run.bands_mean[q * T + sample] += e[row * B + q] / total / R;
    run.total_mean[sample] += total / R;
    if (r != s.mapped) continue;
    for (int q = 0; q < B; ++q) run.bands_one[q * T + sample] = e[row * B + q] / total;
    for (int j = 0; j < bins; ++j)
      run.spectrum_one[j * T + sample] = spectrum.bins()[row * bins + j] / total;
    for (int i = 0; i < N; ++i)
      run.u_one[i * T + sample] = hu(row, i), run.te_one[i * T + sample] = hte(row, i);
  }
}

// All experiments at disorder xi in one batch (experiment-major rows, R rows each), sampled
// every time.sample_every from t = 0.
TonesAtXi run_tones(const TonesSetup& s, double xi, bool progress_on) {
  ChainScene cs = s.cs;
  cs.spec.xi = xi;
  const int R = cs.realizations, N = cs.spec.beads, L = s.L, B = s.B;
  const long T = s.samples + 1;
  TonesAtXi out;
  out.xi = xi;
  std::vector<ToneRun>& runs = out.runs = empty_runs(s, T);
  const int G = static_cast<int>(runs.size());
  std::vector<std::uint64_t> ids;
  for (int g = 0; g < G; ++g)
    for (int r = 0; r < R; ++r) ids.push_back(r);  // the same disorder in every experiment
  ChainBatch<Space> c(cs.spec, ids);
  c.kernel = cs.kernel;
  // chain_set_standing_waves takes one amplitude: set each experiment's rows, then scale.
  std::vector<int> row_tones;
  for (const ToneRun& run : runs) row_tones.insert(row_tones.end(), R, run.tone);
  chain_set_standing_waves(c, row_tones, 1, 1.0);
  {
    auto hu = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.u);
    for (int row = 0; row < c.R; ++row)
      for (int i = 0; i < N; ++i) hu(row, i) *= runs[row / R].u0;
    Kokkos::deep_copy(c.u, hu);
  }
  chain_check_time_step(c, cs.dt);
  chain_accelerations(c);
  const auto t0 = chain_totals(c);
  const auto e0 = cs.spec.force == ChainForce::Hertz ? t0.hertz : t0.linear;
  ChainSpectrum spectrum(c.R, chain_lattice(cs.spec));
  for (ToneRun& run : runs) run.spectrum_one.assign(spectrum.lattice().bins() * T, 0.0);
  Kokkos::View<double**, Kokkos::LayoutRight, Space::memory_space> te("te", c.R, N);
  Progress progress("chain_tones xi=" + std::to_string(cs.spec.xi), s.samples, progress_on);
  for (long sample = 0; sample < T; ++sample) {
    if (sample > 0) chain_advance_guarded(c, cs.dt, s.per_sample, e0, cs.energy_growth);
    out.times.push_back(c.time);
    chain_spectrum(spectrum, c);
    const std::vector<double> e = chain_band_energies(spectrum.bins(), c.R, L, B);
    chain_bead_energies(c, te);
    const auto hte = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), te);
    const auto hu = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.u);
    record_sample(runs, s, sample, e, spectrum, hu, hte, c.R);
    if (sample > 0) progress.update(sample);
  }
  progress.finish();
  return out;
}

std::vector<double> row(const std::vector<double>& m, int r, long T) {
  return std::vector<double>(m.begin() + r * T, m.begin() + (r + 1) * T);
}

// Amplitude check per tone: normalized band energies and u/u0 maps of the first and every
// other amplitude; the energy ratio against (u0 ratio)^2.
std::vector<AmplitudeCheck> amplitude_checks(const TonesSetup& s,
                                             const std::vector<ToneRun>& runs) {
  std::vector<AmplitudeCheck> checks;
  const size_t A = s.amplitudes.size();
  for (size_t ti = 0; ti < s.tones.size(); ++ti) {
    const ToneRun& ref = runs[ti * A];
    for (size_t a = 1; a < A; ++a) {
      const ToneRun& run = runs[ti * A + a];
      double dband = 0, du = 0, umax = 0;
      for (size_t i = 0; i < ref.bands_mean.size(); ++i)
        dband = std::max(dband, std::abs(ref.bands_mean[i] - run.bands_mean[i]));
      for (size_t i = 0; i < ref.u_one.size(); ++i) {
        du = std::max(du, std::abs(ref.u_one[i] / ref.u0 - run.u_one[i] / run.u0));
        umax = std::max(umax, std::abs(ref.u_one[i] / ref.u0));
      }
      AmplitudeCheck c;
      c.tone = ref.tone, c.u0_first = ref.u0, c.u0 = run.u0;
      c.band_difference = dband;
      c.u_difference = du / umax;
      c.energy_ratio = (ref.total_mean[0] / run.total_mean[0]) / std::pow(ref.u0 / run.u0, 2);
      checks.push_back(c);
    }
  }
  return checks;
}

// What the fitting procedures see (first amplitude of the fitted tone).
ToneFits fit_tone(const TonesSetup& s, const std::vector<ToneRun>& runs,
                  const std::vector<double>& times) {
  const long T = s.samples + 1;
  const size_t A = s.amplitudes.size();
  const ToneRun& fr =
      runs[(std::find(s.tones.begin(), s.tones.end(), s.ftone) - s.tones.begin()) * A];
  ToneFits f;
  f.decay = row(fr.bands_mean, s.fband, T);
  f.rise = row(fr.bands_mean, s.nband, T);
  auto slice = [&](const std::vector<double>& v, FitWindow w) {
    return std::vector<double>(v.begin() + w.first, v.begin() + w.last + 1);
  };
  const std::vector<double> t1 = slice(times, s.fw1), t2 = slice(times, s.fw2);
  f.d1 = fit_decay(t1, slice(f.decay, s.fw1));
  f.r1 = fit_rise(t1, slice(f.rise, s.fw1));
  // Procedure 2: straight lines through (t, 1 - e_s) and (t, e_r), least squares through 0.
  auto slope_through_origin = [](const std::vector<double>& t, const std::vector<double>& y) {
    double ty = 0, tt = 0;
    for (size_t i = 0; i < t.size(); ++i) ty += t[i] * y[i], tt += t[i] * t[i];
    return ty / tt;
  };
  std::vector<double> loss = slice(f.decay, s.fw2);
  for (double& e : loss) e = 1 - e;
  f.x1 = slope_through_origin(t2, loss);
  f.x2 = slope_through_origin(t2, slice(f.rise, s.fw2));
  return f;
}

// Every disorder's ensemble, its amplitude checks and fits, a line each as it ends. All are
// kept until the run is written: read_setup's memory check counts every disorder's series.
std::vector<TonesAtXi> run_all(const TonesSetup& s, bool progress) {
  std::vector<TonesAtXi> all;
  for (double xi : s.cs.xis) {
    TonesAtXi x = run_tones(s, xi, progress);
    x.checks = amplitude_checks(s, x.runs);
    x.fits = fit_tone(s, x.runs, x.times);
    const ToneFits& f = x.fits;
    std::cout << "xi = " << xi << ": tone " << s.ftone << " (band " << s.fband << ") keeps "
              << f.decay.back() << " of its energy at t = " << x.times.back() << "; Q_ss "
              << -f.d1.z * (1 - f.d1.y) << " (procedure 1), " << -f.x1 << " (procedure 2)\n";
    all.push_back(std::move(x));
  }
  return all;
}

// Each tone run's series in group g (/xi_<k>).
void write_tone_runs(H5Writer& h5, const std::string& g, const TonesSetup& s,
                     const std::vector<ToneRun>& runs) {
  const long T = s.samples + 1;
  const int bins = static_cast<int>(runs[0].spectrum_one.size() / T);
  for (const ToneRun& run : runs) {
    char name[96];
    std::snprintf(name, sizeof name, "%s/tone_%d_u0_%g", g.c_str(), run.tone, run.u0);
    const std::string t = name;
    const auto TT = static_cast<hsize_t>(T);
    const auto B = static_cast<hsize_t>(s.B), N = static_cast<hsize_t>(s.cs.spec.beads);
    write_quantity(h5, t + "/bands_mean", run.bands_mean, "1", {B, TT});
    write_quantity(h5, t + "/bands_one", run.bands_one, "1", {B, TT});
    write_quantity(h5, t + "/spectrum_one", run.spectrum_one, "1",
                   {static_cast<hsize_t>(bins), TT});
    write_quantity(h5, t + "/u_one", run.u_one, "1", {N, TT});
    write_quantity(h5, t + "/te_one", run.te_one, "1", {N, TT});
    write_quantity(h5, t + "/total_mean", run.total_mean, "1");
    h5.attribute(t, "tone", run.tone);
    h5.attribute(t, "u0", run.u0);
    h5.attribute(t, "band", chain_band_of_bin(run.tone, s.L, s.B));
  }
}

Json amplitude_checks_json(const std::vector<AmplitudeCheck>& checks) {
  Json out = Json::array();
  for (const AmplitudeCheck& a : checks) {
    Json c = Json::object();
    c["tone"] = static_cast<double>(a.tone);
    c["u0"] = std::vector<double>{a.u0_first, a.u0};
    c["max_abs_difference_normalized_band_energies"] = a.band_difference;
    c["max_difference_u_over_u0_relative"] = a.u_difference;
    c["energy_ratio_over_amplitude_ratio_squared"] = a.energy_ratio;
    out.push(c);
  }
  return out;
}

// The fits in group g/fits, and as they go into summary.json.
Json write_fits(H5Writer& h5, const std::string& g, const TonesSetup& s, const ToneFits& f) {
  Json fit = Json::object();
  fit["tone"] = static_cast<double>(s.ftone);
  fit["agitated_band"] = static_cast<double>(s.fband);
  fit["neighbour_band"] = static_cast<double>(s.nband);
  fit["decay_nonlinear"] = std::vector<double>{f.d1.y, f.d1.z};  // (1 - y1) e^{-z1 t} + y1
  fit["rise_nonlinear"] = std::vector<double>{f.r1.y, f.r1.z};   // y2 (1 - e^{-z2 t})
  fit["Q_ss_nonlinear"] = -f.d1.z * (1 - f.d1.y);
  fit["Q_rs_nonlinear"] = f.r1.y * f.r1.z;
  fit["Q_ss_linear"] = -f.x1;
  fit["Q_rs_linear"] = f.x2;
  fit["agitated_band_energy_at_end"] = f.decay.back();
  const std::string fg = g + "/fits";
  // Normalized band energies; the fits' y are fractions and their rates z, x per t_c.
  write_quantity(h5, fg + "/decay", f.decay, "1");
  write_quantity(h5, fg + "/rise", f.rise, "1");
  write_quantity(h5, fg + "/decay_nonlinear", std::vector<double>{f.d1.y, f.d1.z}, "1");
  write_quantity(h5, fg + "/rise_nonlinear", std::vector<double>{f.r1.y, f.r1.z}, "1");
  write_quantity(h5, fg + "/linear_slopes", std::vector<double>{f.x1, f.x2}, "1");
  h5.attribute(fg, "tone", s.ftone);
  h5.attribute(fg, "agitated_band", s.fband);
  h5.attribute(fg, "neighbour_band", s.nband);
  return fit;
}

// results.h5 (a group /xi_<k> per disorder, then the scene's attributes) and summary.json.
void write_results(SceneOutput& output, const TonesSetup& s, const std::vector<TonesAtXi>& xis,
                   const WallClock& clock) {
  H5Writer& h5 = output.h5();
  Json runs_json = Json::array();
  for (size_t k = 0; k < xis.size(); ++k) {
    const TonesAtXi& x = xis[k];
    const std::string g = "/xi_" + std::to_string(k);
    // Reduced units (docs/model_chains.md §1), so every unit is "1": time in t_c, displacement
    // in Delta_0, energies in F_0 Delta_0, band and spectral energies normalized by the total.
    write_quantity(h5, g + "/times", x.times, "1");
    h5.attribute(g, "xi", x.xi);
    write_tone_runs(h5, g, s, x.runs);
    Json xj = Json::object();
    xj["xi"] = x.xi;
    xj["amplitude_check"] = amplitude_checks_json(x.checks);
    xj["fits"] = write_fits(h5, g, s, x.fits);
    runs_json.push(xj);
  }
  h5.attribute("/", "bands", s.B);
  h5.attribute("/", "beads", s.cs.spec.beads);
  h5.attribute("/", "sites", s.L);
  h5.attribute("/", "mapped_realization", s.mapped);
  h5.attribute("/", "window_nonlinear_first", s.fw1.first);
  h5.attribute("/", "window_nonlinear_last", s.fw1.last);
  h5.attribute("/", "window_linear_first", s.fw2.first);
  h5.attribute("/", "window_linear_last", s.fw2.last);
  Json& summary = output.summary();
  summary["tones"] = std::vector<double>(s.tones.begin(), s.tones.end());
  std::vector<double> tone_bands;
  for (int t : s.tones) tone_bands.push_back(chain_band_of_bin(t, s.L, s.B));
  summary["tone_bands"] = tone_bands;
  summary["tone_note"] =
      "u_i = u0 sin(N 2 pi i / L); tone N lies in band (N - 1) B / (L/2), so the source's "
      "N = 4r sits at the upper edge of band r - 1 and a band centre (wave.bands) mid-band";
  summary["runs"] = runs_json;
  summary["wall_seconds"] = clock.seconds();
}

}  // namespace

void run_chain_tones(const SceneFile& scene, const RunOptions& opts) {
  const TonesSetup s = read_setup(scene);
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "chain_tones");
  output.h5();  // the partial results.h5 made now: an unwritable folder fails before the run
  const WallClock clock;
  const std::vector<TonesAtXi> xis = run_all(s, opts.progress);
  write_results(output, s, xis, clock);
  output.finish();
}

}  // namespace granular
