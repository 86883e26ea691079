// Scene `chain_impulse`: an impulse v0 on the first (or centre) bead of disordered chains,
// ensembles per disorder xi. Records the ensemble-mean energy profile <TE_p>(t), the centre
// of energy <R(t)> and the squared width <r^2(t)>, the energy left on the source bead, and
// the near-source decay of the localized energy (chain.md section 6). Every late-time
// quantity is taken before the fastest front (speed sqrt(3/2)) reaches the far end, so that
// no reflection mixes in; the summary says where that analysis window ends.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>

#include "core/progress.hpp"
#include "kernels/chain_energy.hpp"
#include "scenarios/chains/chain_config.hpp"
#include "scenarios/common/power_law_fit.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

using Space = Kokkos::DefaultExecutionSpace;

}  // namespace

void run_chain_impulse(const SceneFile& scene, const RunOptions& opts) {
  ChainScene cs = read_chain_scene(scene);
  const double v0 = scene.real("impulse.v0", 0.01);
  const std::string where = scene.text("impulse.bead", "first");
  const double t_max = scene.real("time.t_max");
  const int decay_span = static_cast<int>(scene.integer("analysis.near_source_beads", 40));
  // The source describes the localized energy as a power law of the distance out to ~800
  // beads: fitted over [1, this], cut at 0.8 of the front's distance at the analysis time.
  const int power_span = static_cast<int>(scene.integer("analysis.power_law_beads", 800));
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
  const long samples = std::lround(t_max / cs.sample_every);

  if (!begin_outputs(opts)) return;
  H5Writer h5(opts.out_dir + "/results.h5");
  Json summary = chain_summary_header(scene, "chain_impulse");
  Json runs = Json::array();
  std::vector<double> xis, residual_means, residual_ratios;
  WallClock total_clock;
  for (size_t k = 0; k < cs.xis.size(); ++k) {
    cs.spec.xi = cs.xis[k];
    WallClock clock;
    ChainBatch<Space> c(cs.spec, ChainBatch<Space>::first(cs.realizations));
    chain_set_impulse(c, source, v0);
    chain_check_time_step(c, cs.dt);
    chain_accelerations(c);
    const auto t0 = chain_totals(c);
    const auto& e0 = cs.spec.force == ChainForce::Hertz ? t0.hertz : t0.linear;
    const double energy0 = 0.5 * v0 * v0;  // ensemble-mean initial energy (mean mass 1)
    Kokkos::View<double**, Kokkos::LayoutRight, Space::memory_space> te("te", c.R, N);
    std::vector<double> times{0.0}, profile, centre{static_cast<double>(source)}, width2{0.0},
        source_energy, source_ratio, drift{0.0};
    // Each realization's source energy against its own initial energy b_source v0^2 / 2.
    const std::vector<double> source_mass = chain_bead_column<Space>(c.b, source);
    auto mean_source_ratio = [&] {
      const std::vector<double> e = chain_bead_column<Space>(te, source);
      double sum = 0;
      for (int r = 0; r < c.R; ++r) sum += e[r] / (0.5 * source_mass[r] * v0 * v0);
      return sum / c.R;
    };
    chain_bead_energies(c, te);
    profile = chain_ensemble_mean<Space>(te);
    source_energy.push_back(profile[source]);
    source_ratio.push_back(mean_source_ratio());
    Progress progress("chain_impulse xi=" + std::to_string(cs.spec.xi), samples, opts.progress);
    for (long s = 1; s <= samples; ++s) {
      const auto t = chain_advance_guarded(c, cs.dt, per_sample, e0, cs.energy_growth);
      chain_bead_energies(c, te);
      const auto mean = chain_ensemble_mean<Space>(te);
      profile.insert(profile.end(), mean.begin(), mean.end());
      source_energy.push_back(mean[source]);
      source_ratio.push_back(mean_source_ratio());
      double R = 0, r2 = 0, worst = 0;
      const auto& conserved = cs.spec.force == ChainForce::Hertz ? t.hertz : t.linear;
      for (int r = 0; r < c.R; ++r) {
        R += t.centre[r] / c.R, r2 += t.width2[r] / c.R;
        worst = std::max(worst, std::abs(conserved[r] / e0[r] - 1));
      }
      times.push_back(c.time), centre.push_back(R), width2.push_back(r2), drift.push_back(worst);
      progress.update(s);
    }
    progress.finish();
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
    for (int d = 1; d <= far_end; ++d)
      dist_far.push_back(d), te_far.push_back(last[source + d] / energy0);
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
    h5.write(g + "/time", times);
    h5.write(g + "/te_mean", profile, {static_cast<hsize_t>(samples + 1), static_cast<hsize_t>(N)});
    h5.write(g + "/centre_mean", centre);
    h5.write(g + "/width2_mean", width2);
    h5.write(g + "/source_energy", source_energy);
    h5.write(g + "/source_fraction_per_realization", source_ratio);
    h5.write(g + "/energy_drift", drift);
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
    run["near_source_decay_per_bead"] = decay_rate;
    run["near_source_beads"] = std::vector<double>{0.0, dist.back()};
    run["localization_length_beads"] = decay_rate > 0 ? Json(1.0 / decay_rate) : Json();
    Json far = Json::object();
    far["beads"] = std::vector<double>{1.0, static_cast<double>(far_end)};
    far["power_law_exponent"] = -far_pow.exponent;  // <TE_p> ~ d^-alpha
    far["power_law_exponent_stderr"] = far_pow.exponent_stderr;
    far["power_law_rms_log_residual"] = far_pow.rms_log_residual;
    far["exponential_decay_per_bead"] = -far_exp.exponent;
    far["exponential_rms_log_residual"] = far_exp.rms_log_residual;
    run["decay_over_long_range"] = far;
    run["centre_of_energy_distance_at_t_max"] = centre.back() - source;
    run["width2_at_t_max"] = width2.back();
    run["width2_growth_exponent"] = exponent;
    run["exponent_fit_window"] = std::vector<double>{0.5 * t_end, times[s_end]};
    run["front_reaches_far_end_at"] = t_front;
    run["max_relative_energy_drift"] = *std::max_element(drift.begin(), drift.end());
    run["wall_seconds"] = seconds;
    run["bead_steps_per_second"] = double(c.R) * N * samples * per_sample / seconds;
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
  against_xi["ratio_of_ensemble_means"] = fit_power_law(xis, residual_means).exponent;
  against_xi["mean_of_realization_fractions"] = fit_power_law(xis, residual_ratios).exponent;
  summary["source_residual_exponent_vs_xi"] = against_xi;
  summary["wall_seconds"] = total_clock.seconds();
  write_text_file(opts.out_dir + "/summary.json", summary.dump());
  if (opts.charts) run_plot_script("chain_impulse.py", opts.out_dir + "/results.h5", opts.out_dir);
}

}  // namespace granular
