// Scene `chain_master_equation`: standing waves agitating one band each, ensembles per
// disorder xi; the ensemble-averaged normalized band energies give the transfer matrix Q
// of the master equation by the spec's two fitting procedures (docs/model_chains.md §5) and by a
// global constrained fit over the whole horizon, with and without a trapped fraction per
// band (weak localization). Each procedure is also fitted on one half of the ensemble and
// judged on the other half; a two-tone run outside the fitting data checks the forward
// prediction against the full ensemble, and times both.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <stdexcept>

#include "core/chain/master_equation.hpp"
#include "core/io/dataset_units.hpp"
#include "core/run/ensemble.hpp"
#include "core/run/progress.hpp"
#include "kernels/chain/chain_energy.hpp"
#include "scenarios/chains/chain_config.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

using Space = Kokkos::DefaultExecutionSpace;

std::vector<double> flatten(const Eigen::MatrixXd& m) {  // row-major
  std::vector<double> out;
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) out.push_back(m(i, j));
  return out;
}

// Runs a batch whose rows start from the standing waves `tones` (tones_each per row, rows
// grouped by experiment, `per_group` realizations each) and returns, per experiment, the
// ensemble-mean normalized band energies (B x samples+1).
struct EnsembleRun {
  std::vector<double> times;
  std::vector<Eigen::MatrixXd> bands;  // one per experiment
  // The same over the first and the second half of the realizations (fit and held out).
  std::vector<Eigen::MatrixXd> half[2];
  double max_imag = 0;
  double seconds = 0;
  long bead_steps = 0;
};

// Runs the experiments `mine` = [first, last) of a batch whose rows start from the standing
// waves `tones` (tones_each per row, rows grouped by experiment, `per_group` realizations
// each) and returns, per experiment run here, the ensemble-mean normalized band energies
// (B x samples+1). Every experiment's means are summed within the experiment, in
// realization order, so which rank runs it changes nothing.
EnsembleRun run_band_ensemble(const ChainScene& cs, const std::vector<int>& tones, int tones_each,
                              std::pair<size_t, size_t> mine, double u0, long samples,
                              long per_sample, int B, const std::string& label, bool progress_on) {
  WallClock clock;
  EnsembleRun out;
  const int groups = static_cast<int>(mine.second - mine.first);
  if (groups == 0) return out;
  const int R = cs.realizations;
  std::vector<std::uint64_t> ids;
  for (int g = 0; g < groups; ++g)
    for (int r = 0; r < R; ++r) ids.push_back(r);  // the same disorder for every experiment
  const auto at = static_cast<std::ptrdiff_t>(mine.first * R * tones_each);
  const std::vector<int> my_tones(tones.begin() + at,
                                  tones.begin() + at + std::ptrdiff_t(groups) * R * tones_each);
  ChainBatch<Space> c(cs.spec, ids);
  c.kernel = cs.kernel;
  chain_set_standing_waves(c, my_tones, tones_each, u0);
  chain_check_time_step(c, cs.dt);
  chain_accelerations(c);
  const auto t0 = chain_totals(c);
  const auto e0 = cs.spec.force == ChainForce::Hertz ? t0.hertz : t0.linear;
  const int L = cs.spec.sites();
  ChainSpectrum spectrum(c.R, chain_lattice(cs.spec));
  out.bands.assign(groups, Eigen::MatrixXd::Zero(B, samples + 1));
  const int first_half = R / 2;
  for (auto& h : out.half) h.assign(groups, Eigen::MatrixXd::Zero(B, samples + 1));
  Progress progress(label, samples, progress_on);
  for (long s = 0; s <= samples; ++s) {
    if (s > 0) chain_advance_guarded(c, cs.dt, per_sample, e0, cs.energy_growth);
    chain_spectrum(spectrum, c);
    out.max_imag = std::max(out.max_imag, spectrum.max_imag());
    const auto e = chain_band_energies(spectrum.bins(), c.R, L, B);
    for (int row = 0; row < c.R; ++row) {
      double total = 0;
      for (int r = 0; r < B; ++r) total += e[row * B + r];
      const int h = row % R < first_half ? 0 : 1;
      const double n = h == 0 ? first_half : R - first_half;
      for (int r = 0; r < B; ++r) {
        out.bands[row / R](r, s) += e[row * B + r] / total / R;
        out.half[h][row / R](r, s) += e[row * B + r] / total / n;
      }
    }
    out.times.push_back(c.time);
    if (s > 0) progress.update(s);
  }
  progress.finish();
  out.seconds = clock.seconds();
  out.bead_steps = static_cast<long>(c.R) * c.N * samples * per_sample;
  return out;
}

// Rank 0: the experiments of every rank in rank order (= experiment order), the largest
// compute time (the ensemble's wall time) and the summed work; other ranks: an empty run.
EnsembleRun gather_band_runs(const EnsembleRun& mine, int B, long samples) {
  Packer p;
  p.put(mine.times).put(mine.max_imag).put(mine.seconds);
  p.put(static_cast<std::int64_t>(mine.bead_steps));
  p.put(static_cast<std::int64_t>(mine.bands.size()));
  for (size_t g = 0; g < mine.bands.size(); ++g)
    for (const Eigen::MatrixXd* m : {&mine.bands[g], &mine.half[0][g], &mine.half[1][g]})
      p.put(std::vector<double>(m->data(), m->data() + m->size()));
  const std::vector<std::string> all = ensemble::gather(p.bytes());
  EnsembleRun out;
  for (const std::string& bytes : all) {
    Unpacker u(bytes);
    std::vector<double> times = u.reals();
    if (out.times.empty()) out.times = std::move(times);
    out.max_imag = std::max(out.max_imag, u.real());
    out.seconds = std::max(out.seconds, u.real());
    out.bead_steps += static_cast<long>(u.integer());
    const std::int64_t n = u.integer();
    for (std::int64_t g = 0; g < n; ++g)
      for (auto* list : {&out.bands, &out.half[0], &out.half[1]}) {
        const std::vector<double> v = u.reals();
        list->push_back(Eigen::Map<const Eigen::MatrixXd>(v.data(), B, samples + 1));
      }
  }
  return out;
}

// The scene's keys, read and checked.
struct MasterSetup {
  ChainScene cs;
  int B = 0;              // bands
  int b1 = 0, b2 = 0;     // the bands of the two-tone validation
  std::string placement;  // where each band's tone sits
  double u0 = 0;
  long samples = 0, check_samples = 0, per_sample = 0;
  FitWindow fw1, fw2, fw3;  // procedures 1, 2 and the global fits
  // The use the reduced model stands for: an ensemble of this size run to this horizon.
  double use_realizations = 0, use_horizon = 0;
};

MasterSetup read_setup(const SceneFile& scene) {
  MasterSetup m;
  ChainScene& cs = m.cs;
  cs = read_chain_scene(scene);
  const int B = m.B = scene.small_integer("bands.count");
  // Where each band's tone sits: its middle bin (default), or its last bin, the source's
  // N = 4, 8, ..., 128 for L = 256 and B = 32 (N = 4r agitates band r - 1).
  m.placement = scene.text("bands.tone_placement", "centre");
  scene.require(m.placement == "centre" || m.placement == "upper_edge", "bands.tone_placement",
                "must be \"centre\" or \"upper_edge\"");
  m.u0 = scene.real("wave.u0", 0.01);
  const long samples = m.samples = scene.small_integer("time.samples");
  const auto w1 = scene.reals("fit.window_nonlinear", {2, 18});
  const auto w2 = scene.reals("fit.window_linear", {2, 8});
  const auto w3 = scene.reals("fit.window_global", {0, static_cast<double>(samples)});
  const auto check_bands = scene.reals("validation.bands");
  m.check_samples = scene.small_integer("validation.samples",
                                        static_cast<int>(std::min<long>(2 * samples, 2147483647)));
  scene.require(!cs.exact, "time.solver",
                "must be \"verlet\" here (the exact solver serves chain_impulse)");
  const int L = cs.spec.sites();
  scene.require(cs.spec.boundary == ChainBoundary::Fixed || L % 2 == 0, "chain.beads",
                "must be even for a periodic ring");
  scene.require(B >= 2 && B <= L / 2, "bands.count",
                "must be between 2 and L/2 = " + std::to_string(L / 2));
  scene.require(m.u0 > 0 && m.u0 < 0.1, "wave.u0", "must be in (0, 0.1)");
  scene.require(samples >= 3, "time.samples", "must be at least 3");
  // Ensemble-mean band energies (B bands x B tone experiments) at every sample, per xi.
  scene.require_memory("time.samples",
                       8.0 * (samples + 1) * B * B * static_cast<double>(cs.xis.size()));
  scene.require_memory("validation.samples",
                       8.0 * (m.check_samples + 1) * B * B * static_cast<double>(cs.xis.size()));
  auto window = [&](const std::vector<double>& w, const char* key) {
    scene.require(w.size() == 2 && w[0] >= 0 && w[1] > w[0] && w[1] <= samples, key,
                  "must be [first, last] sample indices within time.samples");
    return FitWindow{static_cast<int>(w[0]), static_cast<int>(w[1])};
  };
  m.fw1 = window(w1, "fit.window_nonlinear"), m.fw2 = window(w2, "fit.window_linear");
  m.fw3 = window(w3, "fit.window_global");
  scene.require(cs.realizations >= 2, "disorder.realizations",
                "must be at least 2 (half the ensemble is held out to judge the fits)");
  m.use_realizations = scene.real("cost.realizations", 1000);
  m.use_horizon = scene.real("cost.horizon", 1000);
  scene.require(m.use_realizations >= 1, "cost.realizations", "must be at least 1");
  scene.require(m.use_horizon > 0 && m.use_horizon / cs.sample_every <= 1e7, "cost.horizon",
                "must be positive and at most 1e7 sampling intervals");
  scene.require(check_bands.size() == 2 && check_bands[0] >= 0 && check_bands[1] >= 0 &&
                    check_bands[0] < B && check_bands[1] < B && check_bands[0] != check_bands[1],
                "validation.bands", "must be two different band indices in [0, bands.count)");
  scene.require(m.check_samples >= 1, "validation.samples", "must be positive");
  m.per_sample = chain_steps_per_sample(scene, cs);
  scene.reject_unknown_keys();
  m.b1 = static_cast<int>(check_bands[0]), m.b2 = static_cast<int>(check_bands[1]);
  return m;
}

// The ensembles at disorder xi k: the B tone experiments dealt over the ranks, the
// two-tone validation (one experiment) run by the last rank; rank 0 gets both whole.
std::pair<EnsembleRun, EnsembleRun> run_ensembles(MasterSetup& m,
                                                  const std::vector<int>& band_tones, size_t k,
                                                  bool progress) {
  ChainScene& cs = m.cs;
  const int B = m.B, R = cs.realizations;
  cs.spec.xi = cs.xis[k];
  // One experiment per band: R realizations of the chain start from that band's tone.
  std::vector<int> tones;
  for (int s = 0; s < B; ++s) tones.insert(tones.end(), R, band_tones[s]);
  const EnsembleRun fit = gather_band_runs(
      run_band_ensemble(cs, tones, 1, ensemble::my_share(B), m.u0, m.samples, m.per_sample, B,
                        "Q fit xi=" + std::to_string(cs.spec.xi), progress),
      B, m.samples);
  // Validation: two tones together, a state none of the fits saw, run for longer.
  std::vector<int> pair;
  for (int r = 0; r < R; ++r) pair.push_back(band_tones[m.b1]), pair.push_back(band_tones[m.b2]);
  const bool runner = ensemble::rank() == ensemble::size() - 1;
  const EnsembleRun check = gather_band_runs(
      run_band_ensemble(cs, pair, 2, {0, runner ? 1 : 0}, m.u0, m.check_samples, m.per_sample, B,
                        "validation xi=" + std::to_string(cs.spec.xi), progress),
      B, m.check_samples);
  return std::make_pair(fit, check);
}

// The four procedures fitted on the whole ensemble.
struct Fits {
  Eigen::MatrixXd Q1, Q2;  // procedure 1 (non-linear, per entry), procedure 2 (linear)
  GlobalFit G3, G4;        // global, and global with trapped fractions
};
Fits fit_procedures(const EnsembleRun& fit_run, const MasterSetup& m) {
  const BandSeries data{fit_run.times, fit_run.bands};
  return Fits{fit_transfer_matrix_nonlinear(data, m.fw1), fit_transfer_matrix_linear(data, m.fw2),
              fit_transfer_matrix_global(data, m.fw3, false),
              fit_transfer_matrix_global(data, m.fw3, true)};
}

// One procedure fitted on the first half of the realizations, judged on the second half,
// experiment by experiment, from that half's own initial state.
struct HeldOut {
  std::string name;
  std::vector<double> agitated, any;  // per experiment: its agitated band's, any band's error
  std::vector<double> rms;            // the rms error over all bands and experiments, per sample
};

// Each procedure's held-out errors.
std::vector<HeldOut> held_out_errors(const EnsembleRun& fit_run, const MasterSetup& m) {
  const int B = m.B;
  const BandSeries fit_half{fit_run.times, fit_run.half[0]};
  const BandSeries held{fit_run.times, fit_run.half[1]};
  using Predictor = std::function<Eigen::MatrixXd(const Eigen::VectorXd&)>;
  const Eigen::MatrixXd h1 = balance_columns(fit_transfer_matrix_nonlinear(fit_half, m.fw1));
  const Eigen::MatrixXd h2 = fit_transfer_matrix_linear(fit_half, m.fw2);
  const GlobalFit h3 = fit_transfer_matrix_global(fit_half, m.fw3, false);
  const GlobalFit h4 = fit_transfer_matrix_global(fit_half, m.fw3, true);
  // (Named one by one: nvcc's front end does not take braced lists of pairs here.)
  std::vector<std::string> names;
  std::vector<Predictor> predictors;
  names.push_back("nonlinear");
  predictors.push_back(
      [&](const Eigen::VectorXd& e0) { return solve_master_equation(h1, e0, held.times); });
  names.push_back("linear");
  predictors.push_back(
      [&](const Eigen::VectorXd& e0) { return solve_master_equation(h2, e0, held.times); });
  names.push_back("global");
  predictors.push_back(
      [&](const Eigen::VectorXd& e0) { return solve_master_equation(h3.Q, e0, held.times); });
  names.push_back("global_trapped");
  predictors.push_back([&](const Eigen::VectorXd& e0) {
    return solve_master_equation_trapped(h4.Q, h4.trapped, e0, held.times);
  });
  std::vector<HeldOut> out;
  const long n_held = static_cast<long>(held.times.size());
  for (size_t p = 0; p < names.size(); ++p) {
    HeldOut h;
    h.name = names[p];
    h.agitated.assign(B, 0.0), h.any.assign(B, 0.0), h.rms.assign(n_held, 0.0);
    for (int e = 0; e < B; ++e) {
      const Eigen::MatrixXd diff = predictors[p](held.series[e].col(0)) - held.series[e];
      h.agitated[e] = diff.row(e).cwiseAbs().maxCoeff();
      h.any[e] = diff.cwiseAbs().maxCoeff();
      for (long i = 0; i < n_held; ++i) h.rms[i] += diff.col(i).squaredNorm() / (double(B) * B);
    }
    for (auto& x : h.rms) x = std::sqrt(x);
    out.push_back(std::move(h));
  }
  return out;
}

// The four procedures' predictions of the two-tone validation, from its first sample.
struct Predictions {
  Eigen::MatrixXd p1, p2, p3, p4;  // procedure 1 uses the balanced Q (see balance_columns)
  double me_seconds = 0;           // one master-equation solve, procedures 1 and 2
};
Predictions predict_validation(const Fits& f, const EnsembleRun& check) {
  const Eigen::MatrixXd& sim = check.bands[0];
  Predictions p;
  WallClock me_clock;
  p.p1 = solve_master_equation(balance_columns(f.Q1), sim.col(0), check.times);
  p.p2 = solve_master_equation(f.Q2, sim.col(0), check.times);
  p.me_seconds = me_clock.seconds() / 2;
  p.p3 = solve_master_equation(f.G3.Q, sim.col(0), check.times);
  p.p4 = solve_master_equation_trapped(f.G4.Q, f.G4.trapped, sim.col(0), check.times);
  return p;
}

// The realistic use: `cost.realizations` chains to `cost.horizon`, sampled as here, by the
// ensemble (at the speed just measured) or by the trapped-fraction master equation (timed:
// one propagator, then one B x B product per sample).
struct Cost {
  double ensemble_seconds = 0, master_equation_seconds = 0;
};
Cost realistic_cost(const MasterSetup& m, const EnsembleRun& fit_run, const EnsembleRun& check,
                    const Fits& f) {
  const ChainScene& cs = m.cs;
  std::vector<double> times;
  for (double t = 0; t <= m.use_horizon + 1e-9 * m.use_horizon; t += cs.sample_every)
    times.push_back(t);
  const int repeats = 5;
  WallClock clock;
  double sink = 0;
  for (int r = 0; r < repeats; ++r)
    sink += solve_master_equation_trapped(f.G4.Q, f.G4.trapped, check.bands[0].col(0), times)(0, 0);
  Cost c;
  c.master_equation_seconds = clock.seconds() / repeats;
  if (!std::isfinite(sink)) throw std::runtime_error("master equation: non-finite energies");
  const double rate = double(fit_run.bead_steps) / fit_run.seconds;
  c.ensemble_seconds = m.use_realizations * cs.spec.beads * (m.use_horizon / cs.dt) / rate;
  return c;
}

// Everything one disorder gives: its ensembles (the halves dropped once they have given the
// held-out errors: nothing writes them), the fits, their held-out errors, the predictions of
// the validation and the timed realistic use.
struct MasterAtXi {
  double xi = 0;
  EnsembleRun fit_run, check;
  Fits fits;
  std::vector<HeldOut> held_out;
  Predictions predictions;
  Cost cost;
};

// The line of one disorder: the loss rates of the first and last bands and the validation's
// errors by procedures 1 and 2, with the times of both.
void report(const MasterSetup& m, const MasterAtXi& x) {
  const Eigen::MatrixXd &Q1 = x.fits.Q1, &Q2 = x.fits.Q2, &sim = x.check.bands[0];
  const Predictions& p = x.predictions;
  const int B = m.B, b1 = m.b1, b2 = m.b2;
  auto band_error = [&](const Eigen::MatrixXd& pred, int b) {
    return (pred.row(b) - sim.row(b)).cwiseAbs().maxCoeff();
  };
  std::cout << "xi = " << x.xi << ": Q_ss(band 0) = " << Q1(0, 0) << " / " << Q2(0, 0)
            << ", Q_ss(band " << B - 1 << ") = " << Q1(B - 1, B - 1) << " / " << Q2(B - 1, B - 1)
            << "; prediction error bands " << b1 << "," << b2 << ": procedure 1 "
            << band_error(p.p1, b1) << ", " << band_error(p.p1, b2) << ", procedure 2 "
            << band_error(p.p2, b1) << ", " << band_error(p.p2, b2) << " (ensemble "
            << x.check.seconds << " s, master equation " << p.me_seconds << " s)\n";
}

// Every disorder's ensembles, fits, held-out errors, predictions and cost (rank 0; the
// other ranks run their share of the ensembles and get nothing), a line each as it ends.
std::vector<MasterAtXi> run_all(MasterSetup& m, const std::vector<int>& band_tones, bool progress) {
  std::vector<MasterAtXi> all;
  for (size_t k = 0; k < m.cs.xis.size(); ++k) {
    auto [fit_run, check] = run_ensembles(m, band_tones, k, progress);
    if (!ensemble::root()) continue;
    MasterAtXi x;
    x.xi = m.cs.xis[k];
    x.fits = fit_procedures(fit_run, m);
    x.held_out = held_out_errors(fit_run, m);
    x.predictions = predict_validation(x.fits, check);
    for (auto* run : {&fit_run, &check}) run->half[0].clear(), run->half[1].clear();
    x.fit_run = std::move(fit_run), x.check = std::move(check);
    report(m, x);
    x.cost = realistic_cost(m, x.fit_run, x.check, x.fits);
    all.push_back(std::move(x));
  }
  return all;
}

// Group /xi_<k> of results.h5 (after its held-out errors).
void write_xi_group(H5Writer& h5, size_t k, const MasterSetup& m, const MasterAtXi& x) {
  const EnsembleRun &fit_run = x.fit_run, &check = x.check;
  const Fits& f = x.fits;
  const Predictions& p = x.predictions;
  const std::string g = "/xi_" + std::to_string(k);
  const auto BB = static_cast<hsize_t>(m.B);
  // Reduced units (docs/model_chains.md §1), so every unit is "1": times in t_c, the
  // transfer matrices Q in 1/t_c, band energies normalized by the total, fractions.
  write_quantity(h5, g + "/times", fit_run.times, "1");
  std::vector<double> series;
  for (const auto& mat : fit_run.bands) {
    const auto flat = flatten(mat);
    series.insert(series.end(), flat.begin(), flat.end());
  }
  write_quantity(h5, g + "/band_series", series, "1",
                 {BB, BB, static_cast<hsize_t>(m.samples + 1)});
  write_quantity(h5, g + "/Q_nonlinear", flatten(f.Q1), "1", {BB, BB});
  write_quantity(h5, g + "/Q_linear", flatten(f.Q2), "1", {BB, BB});
  write_quantity(h5, g + "/Q_global", flatten(f.G3.Q), "1", {BB, BB});
  write_quantity(h5, g + "/Q_global_trapped", flatten(f.G4.Q), "1", {BB, BB});
  write_quantity(h5, g + "/trapped_fraction",
                 std::vector<double>(f.G4.trapped.data(), f.G4.trapped.data() + m.B), "1");
  write_quantity(h5, g + "/held_out/times", fit_run.times, "1");
  write_quantity(h5, g + "/validation/times", check.times, "1");
  const hsize_t T = check.times.size();
  write_quantity(h5, g + "/validation/simulated", flatten(check.bands[0]), "1", {BB, T});
  write_quantity(h5, g + "/validation/predicted_nonlinear", flatten(p.p1), "1", {BB, T});
  write_quantity(h5, g + "/validation/predicted_linear", flatten(p.p2), "1", {BB, T});
  write_quantity(h5, g + "/validation/predicted_global", flatten(p.p3), "1", {BB, T});
  write_quantity(h5, g + "/validation/predicted_global_trapped", flatten(p.p4), "1", {BB, T});
  h5.attribute(g, "xi", x.xi);
  h5.attribute(g + "/validation", "band_1", m.b1);
  h5.attribute(g + "/validation", "band_2", m.b2);
}

// The two-tone validation's errors in summary.json: per band and over all bands, and the
// times of the ensemble and of the master equation.
Json validation_json(const MasterSetup& m, const MasterAtXi& x) {
  const Eigen::MatrixXd& sim = x.check.bands[0];
  const Predictions& p = x.predictions;
  const int b1 = m.b1, b2 = m.b2;
  auto band_error = [&](const Eigen::MatrixXd& pred, int b) {
    return (pred.row(b) - sim.row(b)).cwiseAbs().maxCoeff();
  };
  Json val = Json::object();
  val["bands"] = std::vector<double>{double(b1), double(b2)};
  val["max_abs_error_nonlinear"] = std::vector<double>{band_error(p.p1, b1), band_error(p.p1, b2)};
  val["max_abs_error_linear"] = std::vector<double>{band_error(p.p2, b1), band_error(p.p2, b2)};
  val["max_abs_error_global"] = std::vector<double>{band_error(p.p3, b1), band_error(p.p3, b2)};
  val["max_abs_error_global_trapped"] =
      std::vector<double>{band_error(p.p4, b1), band_error(p.p4, b2)};
  // Over the fitted horizon only (the Markovian model is fitted up to the window's end).
  const long horizon = std::min<long>(std::max(m.fw1.last, m.fw2.last), x.check.times.size() - 1);
  val["max_abs_error_within_fit_horizon_nonlinear"] =
      (p.p1 - sim).leftCols(horizon + 1).cwiseAbs().maxCoeff();
  val["max_abs_error_within_fit_horizon_linear"] =
      (p.p2 - sim).leftCols(horizon + 1).cwiseAbs().maxCoeff();
  val["max_abs_error_all_bands_nonlinear"] = (p.p1 - sim).cwiseAbs().maxCoeff();
  val["max_abs_error_all_bands_linear"] = (p.p2 - sim).cwiseAbs().maxCoeff();
  val["max_abs_error_all_bands_global"] = (p.p3 - sim).cwiseAbs().maxCoeff();
  val["max_abs_error_all_bands_global_trapped"] = (p.p4 - sim).cwiseAbs().maxCoeff();
  val["ensemble_seconds"] = x.check.seconds;
  val["master_equation_seconds"] = p.me_seconds;
  val["speedup"] = x.check.seconds / std::max(p.me_seconds, 1e-9);
  return val;
}

// The run at one disorder in summary.json: the fitted loss rates, how far each procedure's
// columns are from conserving energy, the held-out and the validation errors.
Json run_json(const MasterSetup& m, const MasterAtXi& x, Json held_out) {
  const int B = m.B;
  const Fits& f = x.fits;
  Json run = Json::object();
  run["xi"] = x.xi;
  std::vector<double> d1, d2, cs1, cs2;
  for (int s = 0; s < B; ++s) {
    d1.push_back(f.Q1(s, s)), d2.push_back(f.Q2(s, s));
    cs1.push_back(f.Q1.col(s).sum()), cs2.push_back(f.Q2.col(s).sum());
  }
  run["diag_Q_nonlinear"] = d1;
  run["diag_Q_linear"] = d2;
  run["column_sums_nonlinear"] = cs1;
  run["column_sums_linear"] = cs2;
  // Procedure 1 fits every entry on its own: how far its columns are from conserving energy.
  double violation = 0;
  for (int c = 0; c < B; ++c) violation = std::max(violation, std::abs(cs1[c] / d1[c]));
  run["nonlinear_max_column_sum_over_diagonal"] = violation;
  std::vector<double> d3, d4, cs4;
  for (int c = 0; c < B; ++c)
    d3.push_back(f.G3.Q(c, c)), d4.push_back(f.G4.Q(c, c)), cs4.push_back(f.G4.Q.col(c).sum());
  run["diag_Q_global"] = d3;
  run["diag_Q_global_trapped"] = d4;
  run["column_sums_global_trapped"] = cs4;
  run["trapped_fraction"] = std::vector<double>(f.G4.trapped.data(), f.G4.trapped.data() + B);
  run["global_fit_rms_residual"] = std::vector<double>{f.G3.rms_residual, f.G4.rms_residual};
  run["global_fit_iterations"] =
      std::vector<double>{double(f.G3.iterations), double(f.G4.iterations)};
  run["held_out"] = std::move(held_out);
  run["max_imaginary_part_relative"] = std::max(x.fit_run.max_imag, x.check.max_imag);
  run["validation"] = validation_json(m, x);
  run["fit_ensemble_seconds"] = x.fit_run.seconds;
  run["bead_steps_per_second"] = double(x.fit_run.bead_steps) / x.fit_run.seconds;
  return run;
}

// The held-out errors: their rms over time in /xi_<k>/held_out, and as summary.json has them.
Json write_held_out(H5Writer& h5, size_t k, const std::vector<HeldOut>& held) {
  Json held_out = Json::object();
  for (const HeldOut& h : held) {
    // The rms error of normalized band energies: a pure number.
    write_quantity(h5, "/xi_" + std::to_string(k) + "/held_out/rms_error_" + h.name, h.rms, "1");
    Json one = Json::object();
    one["max_abs_error_agitated_band"] = h.agitated;
    one["max_abs_error_any_band"] = h.any;
    one["worst_agitated_band_error"] = *std::max_element(h.agitated.begin(), h.agitated.end());
    one["rms_error_at_horizon"] = h.rms.back();
    held_out[h.name] = one;
  }
  return held_out;
}

Json cost_json(const MasterAtXi& x) {
  Json c = Json::object();
  c["xi"] = x.xi;
  c["ensemble_seconds_at_measured_speed"] = x.cost.ensemble_seconds;
  c["master_equation_seconds_measured"] = x.cost.master_equation_seconds;
  c["ratio"] = x.cost.ensemble_seconds / std::max(x.cost.master_equation_seconds, 1e-9);
  return c;
}

// results.h5 (a group /xi_<k> per disorder) and summary.json.
void write_results(SceneOutput& output, const MasterSetup& m, const std::vector<int>& band_tones,
                   const std::vector<MasterAtXi>& xis, const WallClock& clock) {
  Json runs = Json::array(), cost_runs = Json::array();
  for (size_t k = 0; k < xis.size(); ++k) {
    const MasterAtXi& x = xis[k];
    Json held_out = write_held_out(output.h5(), k, x.held_out);
    write_xi_group(output.h5(), k, m, x);
    runs.push(run_json(m, x, std::move(held_out)));
    cost_runs.push(cost_json(x));
  }
  output.h5().attribute("/", "bands", m.B);
  Json& summary = output.summary();
  summary["runs"] = runs;
  summary["band_tones"] = std::vector<double>(band_tones.begin(), band_tones.end());
  summary["tone_placement"] = m.placement;
  Json cost = Json::object();
  cost["realizations"] = m.use_realizations;
  cost["horizon"] = m.use_horizon;
  cost["sample_every"] = m.cs.sample_every;
  cost["per_xi"] = cost_runs;
  summary["cost_for_realistic_use"] = cost;
  summary["wall_seconds"] = clock.seconds();
}

}  // namespace

void run_chain_master_equation(const SceneFile& scene, const RunOptions& opts) {
  MasterSetup m = read_setup(scene);
  if (!begin_outputs(opts)) return;
  const int L = m.cs.spec.sites(), B = m.B;
  std::vector<int> band_tones;
  for (int s = 0; s < B; ++s)
    band_tones.push_back(m.placement == "upper_edge" ? chain_band_edge_tone(s, L, B)
                                                     : chain_band_tone(s, L, B));
  if (!ensemble::root()) {  // rank 0 alone fits, predicts and writes
    run_all(m, band_tones, opts.progress);
    return;
  }
  SceneOutput output(scene, opts, "chain_master_equation");
  output.h5();  // the partial results.h5 made now: an unwritable folder fails before the run
  const WallClock clock;
  const std::vector<MasterAtXi> xis = run_all(m, band_tones, opts.progress);
  write_results(output, m, band_tones, xis, clock);
  output.finish();
}

}  // namespace granular
