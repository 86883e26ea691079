// Scene `chain_impulse`: an impulse v0 on the first (or centre) bead of disordered chains,
// ensembles per disorder xi. Records the ensemble-mean energy profile <TE_p>(t), the centre
// of energy <R(t)> and the squared width <r^2(t)>, the energy left on the source bead, and
// the near-source decay of the localized energy (docs/model_chains.md §6). Every late-time
// quantity is taken before the fastest front (speed sqrt(3/2)) reaches the far end, so that
// no reflection mixes in; the summary says where that analysis window ends.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

#include "core/chain/chain_exact.hpp"
#include "core/io/dataset_units.hpp"
#include "core/run/ensemble.hpp"
#include "core/run/progress.hpp"
#include "kernels/chain/chain_energy.hpp"
#include "scenarios/chains/chain_config.hpp"
#include "scenarios/common/charts.hpp"
#include "scenarios/common/power_law_fit.hpp"
#include "scenarios/common/run_report.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

using Space = Kokkos::DefaultExecutionSpace;

// What the analysis needs, sampled every time.sample_every from t = 0: the ensemble-mean
// bead energies (samples+1 rows of N), centre of energy and squared width, the source
// bead's energy as a mean and as each realization's fraction of its own initial energy, and
// the worst relative drift of a realization's conserved energy.
struct ImpulseSeries {
  std::vector<double> times, profile, centre, width2, source_energy, source_ratio, drift;
  double bead_steps = 0;  // Verlet work (0 for the exact solver)
};

// Realizations are summed in fixed blocks of this many, each block in realization order,
// then the block sums in block order: the ranks of an MPI run take whole blocks, so the
// ensemble means are the same bits whatever the number of ranks (or threads).
constexpr int kRealizationBlock = 32;

// The sums over one block of realizations of the series of ImpulseSeries (drift: the largest).
struct ImpulseBlock {
  std::vector<double> profile, centre, width2, source_energy, source_ratio, drift;
  explicit ImpulseBlock(long T = 0, int N = 0)
      : profile(T * N, 0.0),
        centre(T, 0.0),
        width2(T, 0.0),
        source_energy(T, 0.0),
        source_ratio(T, 0.0),
        drift(T, 0.0) {}
  void pack(Packer& p) const {
    p.put(profile).put(centre).put(width2).put(source_energy).put(source_ratio).put(drift);
  }
  static ImpulseBlock unpack(Unpacker& u) {
    ImpulseBlock b;
    b.profile = u.reals(), b.centre = u.reals(), b.width2 = u.reals();
    b.source_energy = u.reals(), b.source_ratio = u.reals(), b.drift = u.reals();
    return b;
  }
};

// This rank's realizations: whole blocks [first, last) of realizations.
struct BlockRange {
  int first_block = 0, last_block = 0, first = 0, last = 0;
};
BlockRange my_blocks(int realizations) {
  const auto blocks =
      static_cast<size_t>((realizations + kRealizationBlock - 1) / kRealizationBlock);
  const auto [b0, b1] = ensemble::my_share(blocks);
  BlockRange r;
  r.first_block = static_cast<int>(b0), r.last_block = static_cast<int>(b1);
  r.first = std::min(realizations, r.first_block * kRealizationBlock);
  r.last = std::min(realizations, r.last_block * kRealizationBlock);
  return r;
}

std::vector<ImpulseBlock> impulse_verlet(const ChainScene& cs, const BlockRange& mine, int source,
                                         double v0, long samples, long per_sample,
                                         std::vector<double>& times, bool progress_on) {
  const int N = cs.spec.beads, n = mine.last - mine.first;
  const long T = samples + 1;
  std::vector<ImpulseBlock> blocks(mine.last_block - mine.first_block, ImpulseBlock(T, N));
  times.assign(1, 0.0);
  if (n == 0) return blocks;
  std::vector<std::uint64_t> ids(n);
  for (int r = 0; r < n; ++r) ids[r] = static_cast<std::uint64_t>(mine.first + r);
  ChainBatch<Space> c(cs.spec, ids);
  chain_set_impulse(c, source, v0);
  chain_check_time_step(c, cs.dt);
  chain_accelerations(c);
  const auto t0 = chain_totals(c);
  const auto& e0 = cs.spec.force == ChainForce::Hertz ? t0.hertz : t0.linear;
  Kokkos::View<double**, Kokkos::LayoutRight, Space::memory_space> te("te", c.R, N);
  // Each realization's source energy against its own initial energy b_source v0^2 / 2.
  const std::vector<double> source_mass = chain_bead_column<Space>(c.b, source);
  auto block_of = [&](int r) { return r / kRealizationBlock - mine.first_block; };
  auto record = [&](long s, const ChainTotals* t) {
    chain_bead_energies(c, te);
    const auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), te);
    for (int r = 0; r < n; ++r) {
      ImpulseBlock& b = blocks[block_of(mine.first + r)];
      double* row = b.profile.data() + s * N;
      for (int i = 0; i < N; ++i) row[i] += h(r, i);
      b.source_energy[s] += h(r, source);
      b.source_ratio[s] += h(r, source) / (0.5 * source_mass[r] * v0 * v0);
      if (t) {
        const auto& conserved = cs.spec.force == ChainForce::Hertz ? t->hertz : t->linear;
        b.centre[s] += t->centre[r], b.width2[s] += t->width2[r];
        b.drift[s] = std::max(b.drift[s], std::abs(conserved[r] / e0[r] - 1));
      } else {
        b.centre[s] += source;
      }
    }
  };
  record(0, nullptr);
  Progress progress("chain_impulse xi=" + std::to_string(cs.spec.xi), samples, progress_on);
  for (long s = 1; s <= samples; ++s) {
    const auto t = chain_advance_guarded(c, cs.dt, per_sample, e0, cs.energy_growth);
    record(s, &t);
    times.push_back(c.time);
    progress.update(s);
  }
  progress.finish();
  return blocks;
}

// The linearized chain solved exactly (docs/model_chains.md §1): each realization's eigenmodes,
// then the state at every sample time in closed form, so neither a time step nor a mass
// floor limits it. Realizations go in batches of a fixed size, each batch's modes computed
// in parallel, and the sums are taken in realization order: the result does not depend on
// the thread count.
std::vector<ImpulseBlock> impulse_exact(const ChainScene& cs, const BlockRange& mine, int source,
                                        double v0, long samples, std::vector<double>& times,
                                        bool progress_on) {
  using Host = Kokkos::DefaultHostExecutionSpace;
  const int N = cs.spec.beads, batch = 8;
  static_assert(kRealizationBlock % 8 == 0, "a batch never straddles two blocks");
  const long T = samples + 1;
  const bool periodic = cs.spec.boundary == ChainBoundary::Periodic;
  std::vector<ImpulseBlock> blocks(mine.last_block - mine.first_block, ImpulseBlock(T, N));
  times.clear();
  for (long s = 0; s < T; ++s) times.push_back(s * cs.sample_every);
  const int n_all = mine.last - mine.first;
  Progress progress("chain_impulse (exact) xi=" + std::to_string(cs.spec.xi),
                    (n_all + batch - 1) / batch, progress_on);
  for (int first = mine.first; first < mine.last; first += batch) {
    const int n = std::min(batch, mine.last - first);
    ImpulseBlock& blk = blocks[first / kRealizationBlock - mine.first_block];
    std::vector<std::uint64_t> ids(n);
    for (int r = 0; r < n; ++r) ids[r] = static_cast<std::uint64_t>(first + r);
    ChainBatch<Host> c(cs.spec, ids);
    chain_set_impulse(c, source, v0);
    const std::vector<double> e0 = chain_totals(c).linear;
    std::vector<std::unique_ptr<ChainExactSolution>> modes(n);
    auto u = c.u, v = c.v, b = c.b, klin = c.klin;
    Kokkos::parallel_for("chain::exact_modes", Kokkos::RangePolicy<Host>(0, n), [&](const int r) {
      modes[r] = std::make_unique<ChainExactSolution>(
          std::vector<double>(&b(r, 0), &b(r, 0) + N),
          std::vector<double>(&klin(r, 0), &klin(r, 0) + c.C), periodic);
      Eigen::VectorXd v_start = Eigen::VectorXd::Zero(N);
      v_start(source) = v0;
      modes[r]->set_initial(Eigen::VectorXd::Zero(N), v_start);
    });
    Kokkos::View<double**, Kokkos::LayoutRight, Host::memory_space> te("te", n, N);
    for (long s = 0; s < T; ++s) {
      Kokkos::parallel_for("chain::exact_state", Kokkos::RangePolicy<Host>(0, n), [&](const int r) {
        Eigen::VectorXd us, vs;
        modes[r]->state(times[s], us, vs);
        for (int i = 0; i < N; ++i) u(r, i) = us(i), v(r, i) = vs(i);
      });
      chain_bead_energies(c, te);
      const auto tot = chain_totals(c);
      for (int r = 0; r < n; ++r) {
        for (int i = 0; i < N; ++i) blk.profile[s * N + i] += te(r, i);
        blk.source_energy[s] += te(r, source);
        blk.source_ratio[s] += te(r, source) / (0.5 * b(r, source) * v0 * v0);
        blk.centre[s] += tot.centre[r], blk.width2[s] += tot.width2[r];
        blk.drift[s] = std::max(blk.drift[s], std::abs(tot.linear[r] / e0[r] - 1));
      }
    }
    progress.update((first - mine.first + n + batch - 1) / batch);
  }
  progress.finish();
  return blocks;
}

// Rank 0: every rank's blocks, summed in block order into the ensemble means (other ranks:
// an empty series).
ImpulseSeries ensemble_series(const std::vector<ImpulseBlock>& mine,
                              const std::vector<double>& times, int realizations) {
  Packer p;
  p.put(static_cast<std::int64_t>(mine.size()));
  for (const ImpulseBlock& b : mine) b.pack(p);
  const std::vector<std::string> parts = ensemble::gather(p.bytes());
  ImpulseSeries out;
  if (!ensemble::root()) return out;
  const long T = static_cast<long>(times.size());
  out.times = times;
  ImpulseBlock sum(T, static_cast<int>(mine.empty() ? 0 : mine[0].profile.size() / T));
  for (const std::string& bytes : parts) {
    Unpacker u(bytes);
    const std::int64_t n = u.integer();
    for (std::int64_t k = 0; k < n; ++k) {
      const ImpulseBlock b = ImpulseBlock::unpack(u);
      for (size_t i = 0; i < sum.profile.size(); ++i) sum.profile[i] += b.profile[i];
      for (long s = 0; s < T; ++s) {
        sum.centre[s] += b.centre[s], sum.width2[s] += b.width2[s];
        sum.source_energy[s] += b.source_energy[s], sum.source_ratio[s] += b.source_ratio[s];
        sum.drift[s] = std::max(sum.drift[s], b.drift[s]);
      }
    }
  }
  for (auto* series :
       {&sum.profile, &sum.source_energy, &sum.source_ratio, &sum.centre, &sum.width2})
    for (double& x : *series) x /= realizations;
  out.profile = std::move(sum.profile), out.centre = std::move(sum.centre);
  out.width2 = std::move(sum.width2), out.source_energy = std::move(sum.source_energy);
  out.source_ratio = std::move(sum.source_ratio), out.drift = std::move(sum.drift);
  return out;
}

}  // namespace

void run_chain_impulse(const SceneFile& scene, const RunOptions& opts) {
  ChainScene cs = read_chain_scene(scene);
  const double v0 = scene.real("impulse.v0", 0.01);
  const std::string where = scene.text("impulse.bead", "first");
  const double t_max = scene.real("time.t_max");
  const int decay_span = scene.small_integer("analysis.near_source_beads", 40);
  // The source describes the localized energy as a power law of the distance out to ~800
  // beads: fitted over [1, this], cut at 0.8 of the front's distance at the analysis time.
  const int power_span = scene.small_integer("analysis.power_law_beads", 800);
  scene.require(where == "first" || where == "centre", "impulse.bead", "must be first or centre");
  scene.require(v0 > 0 && v0 < 0.5, "impulse.v0",
                "must be in (0, 0.5): small against the pre-compression");
  scene.require(t_max >= cs.sample_every, "time.t_max", "must be at least one sample interval");
  scene.require(decay_span >= 3, "analysis.near_source_beads", "must be at least 3");
  scene.require(power_span >= 3, "analysis.power_law_beads", "must be at least 3");
  const long per_sample = chain_steps_per_sample(scene, cs);
  scene.reject_unknown_keys();
  const int N = cs.spec.beads;
  const int source = where == "first" ? 0 : N / 2;
  scene.require(t_max / cs.sample_every <= 1e9, "time.t_max",
                "asks for more than 1e9 samples of time.sample_every");
  const long samples = std::lround(t_max / cs.sample_every);
  // Every block of realizations keeps an energy profile per sample and bead, and the
  // ensemble series another: refused here, naming the key, rather than failing to allocate.
  const double blocks = std::ceil(double(cs.realizations) / kRealizationBlock);
  scene.require_memory("time.t_max", 8.0 * (blocks + 2) * (samples + 1.0) * (N + 6.0));

  if (!begin_outputs(opts)) return;
  // This rank's blocks of realizations at disorder xi k; rank 0 gets the ensemble series of
  // every rank's blocks (the other ranks an empty one).
  auto run_xi = [&](size_t k) {
    cs.spec.xi = cs.xis[k];
    const BlockRange mine = my_blocks(cs.realizations);
    std::vector<double> sample_times;
    const std::vector<ImpulseBlock> blocks =
        cs.exact ? impulse_exact(cs, mine, source, v0, samples, sample_times, opts.progress)
                 : impulse_verlet(cs, mine, source, v0, samples, per_sample, sample_times,
                                  opts.progress);
    ImpulseSeries series = ensemble_series(blocks, sample_times, cs.realizations);
    if (!cs.exact) series.bead_steps = double(cs.realizations) * N * samples * per_sample;
    return series;
  };
  if (!ensemble::root()) {  // rank 0 alone analyses and writes
    for (size_t k = 0; k < cs.xis.size(); ++k) run_xi(k);
    return;
  }
  H5Writer h5(opts.out_dir + "/results.h5");
  Json summary = scene_summary(scene, "chain_impulse");
  Json runs = Json::array();
  std::vector<double> xis, residual_means, residual_ratios;
  WallClock total_clock;
  for (size_t k = 0; k < cs.xis.size(); ++k) {
    cs.spec.xi = cs.xis[k];
    WallClock clock;
    const ImpulseSeries run_series = run_xi(k);
    const auto& times = run_series.times;
    const auto& profile = run_series.profile;
    const auto& centre = run_series.centre;
    const auto& width2 = run_series.width2;
    const auto& source_energy = run_series.source_energy;
    const auto& source_ratio = run_series.source_ratio;
    const auto& drift = run_series.drift;
    const double energy0 = 0.5 * v0 * v0;  // ensemble-mean initial energy (mean mass 1)
    const double seconds = clock.seconds();
    // The analysis window ends before the fastest front reaches the far end and reflects.
    const double t_front = (N - 1 - source) / std::sqrt(1.5);
    const double t_end = std::min(t_max, 0.95 * t_front);
    long s_end = 1;
    while (s_end < samples && times[s_end + 1] <= t_end) ++s_end;
    // Energy left on the source bead: mean over the last tenth of the window, as a ratio of
    // ensemble means (<TE_source> / (v0^2/2), the mean mass being 1) and as the mean of each
    // realization's fraction of its own initial energy <TE_source / (b_source v0^2/2)>.
    const long tail = std::max(1L, s_end / 10);
    double residual = 0, residual_ratio = 0;
    for (long s = s_end - tail + 1; s <= s_end; ++s)
      residual += source_energy[s] / tail, residual_ratio += source_ratio[s] / tail;
    // Near-source decay of <TE_p> at the window's end: an exponential over the first beads
    // (localization length), and a power law against an exponential over the long range.
    const double* last = profile.data() + s_end * N;
    std::vector<double> dist, te_near, dist_far, te_far;
    for (int d = 0; d < decay_span && source + d < N; ++d)
      dist.push_back(d), te_near.push_back(last[source + d] / energy0);
    const int far_end = std::min(
        {power_span, N - 1 - source, static_cast<int>(0.8 * std::sqrt(1.5) * times[s_end])});
    // Up to 193 distances spaced evenly in log d from 1 to far_end (each bead once), so that
    // every decade weighs the same in both fits, as it does on the log-log chart.
    for (int step = 0, prev = 0; far_end >= 1 && step <= 64 * 3; ++step) {
      const int d = static_cast<int>(std::lround(std::pow(far_end, step / (64.0 * 3))));
      if (d > prev) dist_far.push_back(d), te_far.push_back(last[source + d] / energy0);
      prev = std::max(prev, d);
    }
    const PowerLawFit near_exp = fit_exponential(dist, te_near);
    const PowerLawFit far_pow = fit_power_law(dist_far, te_far);
    const PowerLawFit far_exp = fit_exponential(dist_far, te_far);
    const double decay_rate = -near_exp.exponent;
    // Spreading exponent: r^2 ~ t^a (a = 2 is ballistic) over the window's second half.
    std::vector<double> tw, w2;
    for (long s = 1; s <= s_end; ++s)
      if (times[s] >= 0.5 * t_end) tw.push_back(times[s]), w2.push_back(width2[s]);
    const double exponent = fit_power_law(tw, w2).exponent;
    xis.push_back(cs.spec.xi), residual_means.push_back(residual / energy0);
    residual_ratios.push_back(residual_ratio);
    const std::string g = "/xi_" + std::to_string(k);
    // Reduced units (docs/model_chains.md §1), so every unit is "1": time in t_c, energies in
    // F_0 Delta_0 (= m_0 Delta_0^2 / t_c^2), centre and width in bead indices; the source
    // fraction and the drift are ratios.
    write_quantity(h5, g + "/time", times, "1");
    write_quantity(h5, g + "/te_mean", profile, "1",
                   {static_cast<hsize_t>(samples + 1), static_cast<hsize_t>(N)});
    write_quantity(h5, g + "/centre_mean", centre, "1");
    write_quantity(h5, g + "/width2_mean", width2, "1");
    write_quantity(h5, g + "/source_energy", source_energy, "1");
    write_quantity(h5, g + "/source_fraction_per_realization", source_ratio, "1");
    write_quantity(h5, g + "/energy_drift", drift, "1");
    h5.attribute(g, "xi", cs.spec.xi);
    h5.attribute(g, "t_front_far_end", t_front);
    h5.attribute(g, "analysis_end_sample", static_cast<double>(s_end));
    h5.attribute(g, "near_exponential_rate", near_exp.exponent);
    h5.attribute(g, "near_exponential_prefactor", near_exp.prefactor);
    h5.attribute(g, "near_beads", static_cast<double>(dist.size()));
    h5.attribute(g, "far_beads", static_cast<double>(far_end));
    h5.attribute(g, "far_power_law_exponent", far_pow.exponent);
    h5.attribute(g, "far_power_law_prefactor", far_pow.prefactor);
    h5.attribute(g, "far_exponential_rate", far_exp.exponent);
    h5.attribute(g, "far_exponential_prefactor", far_exp.prefactor);
    Json run = Json::object();
    run["xi"] = cs.spec.xi;
    run["analysis_end_time"] = times[s_end];
    run["source_residual_ratio_of_ensemble_means"] = residual / energy0;
    run["source_residual_mean_of_realization_fractions"] = residual_ratio;
    run["near_source_decay_per_bead"] = Json::or_null(decay_rate);
    run["near_source_beads"] = std::vector<double>{0.0, dist.back()};
    run["localization_length_beads"] = decay_rate > 0 ? Json(1.0 / decay_rate) : Json();
    Json far = Json::object();
    far["beads"] = std::vector<double>{1.0, static_cast<double>(far_end)};
    far["points"] = static_cast<double>(dist_far.size());
    far["power_law_exponent"] = Json::or_null(-far_pow.exponent);  // <TE_p> ~ d^-alpha
    far["power_law_exponent_stderr"] = Json::or_null(far_pow.exponent_stderr);
    far["power_law_rms_log_residual"] = Json::or_null(far_pow.rms_log_residual);
    far["exponential_decay_per_bead"] = Json::or_null(-far_exp.exponent);
    far["exponential_rms_log_residual"] = Json::or_null(far_exp.rms_log_residual);
    run["decay_over_long_range"] = far;
    run["centre_of_energy_distance_at_t_max"] = centre.back() - source;
    run["width2_at_t_max"] = width2.back();
    run["width2_growth_exponent"] = Json::or_null(exponent);  // too few points: undefined
    run["exponent_fit_window"] = std::vector<double>{0.5 * t_end, times[s_end]};
    run["front_reaches_far_end_at"] = t_front;
    run["max_relative_energy_drift"] = *std::max_element(drift.begin(), drift.end());
    run["wall_seconds"] = seconds;
    run["solver"] = cs.exact ? "exact" : "verlet";
    if (cs.exact)
      run["seconds_per_realization"] = seconds / cs.realizations;
    else
      run["bead_steps_per_second"] = run_series.bead_steps / seconds;
    runs.push(run);
    const double worst_drift = *std::max_element(drift.begin(), drift.end());
    if (worst_drift > 0.01)
      std::cerr << "warning: xi = " << cs.spec.xi << ": the energy of some realization drifted by "
                << 100 * worst_drift << " % (Verlet near the stability limit of its lightest "
                << "beads); a smaller time.dt or a larger disorder.min_mass reduces it\n";
    std::cout << "xi = " << cs.spec.xi << ": source keeps " << residual / energy0
              << " of the energy (" << residual_ratio << " per realization), r^2 ~ t^" << exponent
              << ", R - source = " << centre.back() - source << " (" << seconds << " s)\n";
  }
  h5.attribute("/", "source", source);
  h5.attribute("/", "energy0", 0.5 * v0 * v0);
  h5.attribute("/", "beads", N);
  h5.commit();
  summary["runs"] = runs;
  // Late-time source energy against disorder, a power law over the xi > 0 runs.
  Json against_xi = Json::object();
  against_xi["ratio_of_ensemble_means"] =
      Json::or_null(fit_power_law(xis, residual_means).exponent);
  against_xi["mean_of_realization_fractions"] =
      Json::or_null(fit_power_law(xis, residual_ratios).exponent);
  summary["source_residual_exponent_vs_xi"] = against_xi;
  summary["wall_seconds"] = total_clock.seconds();
  write_scene_summary(opts, summary);
  if (opts.charts) run_plot_script("chain_impulse.py", opts.out_dir + "/results.h5", opts.out_dir);
}

}  // namespace granular
