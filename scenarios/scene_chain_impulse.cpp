// Scene `chain_impulse`: an impulse v0 on the first (or centre) bead of disordered chains,
// ensembles per disorder xi. Records the ensemble-mean energy profile <TE_p>(t), the centre
// of energy <R(t)> and the squared width <r^2(t)>, the energy left on the source bead, and
// the near-source decay of the localized energy (chain.md section 6).
#include <Kokkos_Core.hpp>
#include <cmath>
#include <iostream>

#include "core/progress.hpp"
#include "kernels/chain_energy.hpp"
#include "scenarios/chain_config.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

using Space = Kokkos::DefaultExecutionSpace;

// Least-squares slope of y on x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= x.size(), my /= y.size();
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i)
    sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxx > 0 ? sxy / sxx : 0.0;
}

}  // namespace

void run_chain_impulse(const SceneFile& scene, const RunOptions& opts) {
  ChainScene cs = read_chain_scene(scene);
  const double v0 = scene.real("impulse.v0", 0.01);
  const std::string where = scene.text("impulse.bead", "first");
  const double t_max = scene.real("time.t_max");
  const int decay_span = static_cast<int>(scene.integer("analysis.near_source_beads", 40));
  scene.require(where == "first" || where == "centre", "impulse.bead", "must be first or centre");
  scene.require(v0 > 0 && v0 < 0.5, "impulse.v0",
                "must be in (0, 0.5): small against the pre-compression");
  scene.require(t_max >= cs.sample_every, "time.t_max", "must be at least one sample interval");
  scene.require(decay_span >= 3, "analysis.near_source_beads", "must be at least 3");
  const long per_sample = chain_steps_per_sample(scene, cs);
  scene.reject_unknown_keys();
  const int N = cs.spec.beads;
  const int source = where == "first" ? 0 : N / 2;
  const long samples = std::lround(t_max / cs.sample_every);

  if (!begin_outputs(opts)) return;
  H5Writer h5(opts.out_dir + "/results.h5");
  Json summary = chain_summary_header(scene, "chain_impulse");
  Json runs = Json::array();
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
        source_energy, drift{0.0};
    chain_bead_energies(c, te);
    profile = chain_ensemble_mean<Space>(te);
    source_energy.push_back(profile[source]);
    Progress progress("chain_impulse xi=" + std::to_string(cs.spec.xi), samples, opts.progress);
    for (long s = 1; s <= samples; ++s) {
      const auto t = chain_advance_guarded(c, cs.dt, per_sample, e0, cs.energy_growth);
      chain_bead_energies(c, te);
      const auto mean = chain_ensemble_mean<Space>(te);
      profile.insert(profile.end(), mean.begin(), mean.end());
      source_energy.push_back(mean[source]);
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
    // Energy left on the source bead: mean over the last tenth of the run.
    const long tail = std::max(1L, samples / 10);
    double residual = 0;
    for (long s = samples - tail + 1; s <= samples; ++s) residual += source_energy[s] / tail;
    // Near-source decay: log <TE_p>(t_max) against distance from the source.
    const double* last = profile.data() + samples * N;
    std::vector<double> dist, logte;
    for (int d = 0; d < decay_span && source + d < N; ++d)
      if (last[source + d] > 0)
        dist.push_back(d), logte.push_back(std::log(last[source + d] / energy0));
    const double decay_rate = -slope(dist, logte);
    // Spreading exponent: r^2 ~ t^a (a = 2 is ballistic) over the second half of the time
    // before the fastest front (speed sqrt(3/2)) reaches the far end and reflects.
    const double t_front = (N - 1 - source) / std::sqrt(1.5);
    const double t_end = std::min(t_max, 0.95 * t_front);
    std::vector<double> lt, lw;
    for (long s = 1; s <= samples; ++s)
      if (times[s] >= 0.5 * t_end && times[s] <= t_end && width2[s] > 0)
        lt.push_back(std::log(times[s])), lw.push_back(std::log(width2[s]));
    const double exponent = slope(lt, lw);
    const std::string g = "/xi_" + std::to_string(k);
    h5.write(g + "/time", times);
    h5.write(g + "/te_mean", profile, {static_cast<hsize_t>(samples + 1), static_cast<hsize_t>(N)});
    h5.write(g + "/centre_mean", centre);
    h5.write(g + "/width2_mean", width2);
    h5.write(g + "/source_energy", source_energy);
    h5.write(g + "/energy_drift", drift);
    h5.attribute(g, "xi", cs.spec.xi);
    h5.attribute(g, "t_front_far_end", t_front);
    Json run = Json::object();
    run["xi"] = cs.spec.xi;
    run["source_residual_fraction"] = residual / energy0;
    run["near_source_decay_per_bead"] = decay_rate;
    run["localization_length_beads"] = decay_rate > 0 ? Json(1.0 / decay_rate) : Json();
    run["centre_of_energy_distance_at_t_max"] = centre.back() - source;
    run["width2_at_t_max"] = width2.back();
    run["width2_growth_exponent"] = exponent;
    run["exponent_fit_window"] = std::vector<double>{0.5 * t_end, t_end};
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
              << " of the energy, r^2 ~ t^" << exponent
              << ", R - source = " << centre.back() - source << " (" << seconds << " s)\n";
  }
  h5.attribute("/", "source", source);
  h5.attribute("/", "energy0", 0.5 * v0 * v0);
  h5.attribute("/", "beads", N);
  h5.commit();
  summary["runs"] = runs;
  summary["wall_seconds"] = total_clock.seconds();
  write_text_file(opts.out_dir + "/summary.json", summary.dump());
  if (opts.charts) run_plot_script("chain_impulse.py", opts.out_dir + "/results.h5", opts.out_dir);
}

}  // namespace granular
