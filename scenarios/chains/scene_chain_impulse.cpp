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
#include "scenarios/common/power_law_fit.hpp"
#include "scenarios/common/scene_output.hpp"
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
  c.kernel = cs.kernel;
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

// The scene's keys, read and checked.
struct ImpulseSetup {
  ChainScene cs;
  double v0 = 0, t_max = 0;
  int source = 0;  // the struck bead: the first, or the centre
  // Near-source beads fitted by an exponential; the source describes the localized energy as
  // a power law of the distance out to ~800 beads: fitted over [1, power_span], cut at 0.8 of
  // the front's distance at the analysis time.
  int decay_span = 0, power_span = 0;
  long per_sample = 0, samples = 0;
};

ImpulseSetup read_setup(const SceneFile& scene) {
  ImpulseSetup s;
  ChainScene& cs = s.cs;
  cs = read_chain_scene(scene);
  s.v0 = scene.real("impulse.v0", 0.01);
  const std::string where = scene.text("impulse.bead", "first");
  s.t_max = scene.real("time.t_max");
  s.decay_span = scene.small_integer("analysis.near_source_beads", 40);
  s.power_span = scene.small_integer("analysis.power_law_beads", 800);
  scene.require(where == "first" || where == "centre", "impulse.bead", "must be first or centre");
  scene.require(s.v0 > 0 && s.v0 < 0.5, "impulse.v0",
                "must be in (0, 0.5): small against the pre-compression");
  scene.require(s.t_max >= cs.sample_every, "time.t_max", "must be at least one sample interval");
  scene.require(s.decay_span >= 3, "analysis.near_source_beads", "must be at least 3");
  scene.require(s.power_span >= 3, "analysis.power_law_beads", "must be at least 3");
  s.per_sample = chain_steps_per_sample(scene, cs);
  scene.reject_unknown_keys();
  const int N = cs.spec.beads;
  s.source = where == "first" ? 0 : N / 2;
  scene.require(s.t_max / cs.sample_every <= 1e9, "time.t_max",
                "asks for more than 1e9 samples of time.sample_every");
  s.samples = std::lround(s.t_max / cs.sample_every);
  // Every block of realizations keeps an energy profile per sample and bead and their sum
  // another, and the ensemble series of every disorder (a profile each) are kept until the
  // run is written: refused here, naming the key, rather than failing to allocate.
  const double blocks = std::ceil(double(cs.realizations) / kRealizationBlock);
  const double series = static_cast<double>(cs.xis.size());
  scene.require_memory("time.t_max", 8.0 * (blocks + 1 + series) * (s.samples + 1.0) * (N + 6.0));
  return s;
}

// This rank's blocks of realizations at disorder xi k; rank 0 gets the ensemble series of
// every rank's blocks (the other ranks an empty one).
ImpulseSeries run_xi(ImpulseSetup& s, size_t k, bool progress) {
  ChainScene& cs = s.cs;
  cs.spec.xi = cs.xis[k];
  const BlockRange mine = my_blocks(cs.realizations);
  std::vector<double> sample_times;
  const std::vector<ImpulseBlock> blocks =
      cs.exact ? impulse_exact(cs, mine, s.source, s.v0, s.samples, sample_times, progress)
               : impulse_verlet(cs, mine, s.source, s.v0, s.samples, s.per_sample, sample_times,
                                progress);
  ImpulseSeries series = ensemble_series(blocks, sample_times, cs.realizations);
  if (!cs.exact)
    series.bead_steps = double(cs.realizations) * cs.spec.beads * s.samples * s.per_sample;
  return series;
}

// What one disorder's ensemble series shows: the energy left on the source, its decay with
// the distance near the source and over the long range, and the spreading exponent.
struct ImpulseAnalysis {
  double energy0 = 0;  // ensemble-mean initial energy (mean mass 1)
  double t_front = 0;  // when the fastest front reaches the far end
  double t_end = 0;    // the analysis window's end, before it does
  long s_end = 1;      // its last sample
  double residual = 0, residual_ratio = 0;
  std::vector<double> dist;  // the near-source distances fitted
  int far_end = 0;           // the long range's last distance
  std::vector<double> dist_far;
  PowerLawFit near_exp, far_pow, far_exp;
  double exponent = 0;  // r^2 ~ t^exponent
};

ImpulseAnalysis analyse(const ImpulseSetup& s, const ImpulseSeries& run) {
  const int N = s.cs.spec.beads, source = s.source;
  const auto& times = run.times;
  ImpulseAnalysis a;
  a.energy0 = 0.5 * s.v0 * s.v0;
  // The analysis window ends before the fastest front reaches the far end and reflects.
  a.t_front = (N - 1 - source) / std::sqrt(1.5);
  a.t_end = std::min(s.t_max, 0.95 * a.t_front);
  long& s_end = a.s_end;
  while (s_end < s.samples && times[s_end + 1] <= a.t_end) ++s_end;
  // Energy left on the source bead: mean over the last tenth of the window, as a ratio of
  // ensemble means (<TE_source> / (v0^2/2), the mean mass being 1) and as the mean of each
  // realization's fraction of its own initial energy <TE_source / (b_source v0^2/2)>.
  const long tail = std::max(1L, s_end / 10);
  for (long t = s_end - tail + 1; t <= s_end; ++t)
    a.residual += run.source_energy[t] / tail, a.residual_ratio += run.source_ratio[t] / tail;
  // Near-source decay of <TE_p> at the window's end: an exponential over the first beads
  // (localization length), and a power law against an exponential over the long range.
  const double* last = run.profile.data() + s_end * N;
  std::vector<double> te_near, te_far;
  for (int d = 0; d < s.decay_span && source + d < N; ++d)
    a.dist.push_back(d), te_near.push_back(last[source + d] / a.energy0);
  a.far_end = std::min(
      {s.power_span, N - 1 - source, static_cast<int>(0.8 * std::sqrt(1.5) * times[s_end])});
  // Up to 193 distances spaced evenly in log d from 1 to far_end (each bead once), so that
  // every decade weighs the same in both fits, as it does on the log-log chart.
  for (int step = 0, prev = 0; a.far_end >= 1 && step <= 64 * 3; ++step) {
    const int d = static_cast<int>(std::lround(std::pow(a.far_end, step / (64.0 * 3))));
    if (d > prev) a.dist_far.push_back(d), te_far.push_back(last[source + d] / a.energy0);
    prev = std::max(prev, d);
  }
  a.near_exp = fit_exponential(a.dist, te_near);
  a.far_pow = fit_power_law(a.dist_far, te_far);
  a.far_exp = fit_exponential(a.dist_far, te_far);
  // Spreading exponent: r^2 ~ t^a (a = 2 is ballistic) over the window's second half.
  std::vector<double> tw, w2;
  for (long t = 1; t <= s_end; ++t)
    if (times[t] >= 0.5 * a.t_end) tw.push_back(times[t]), w2.push_back(run.width2[t]);
  a.exponent = fit_power_law(tw, w2).exponent;
  return a;
}

// One disorder's ensemble series, what it shows, and its wall time (rank 0).
struct ImpulseAtXi {
  double xi = 0;
  ImpulseSeries series;
  ImpulseAnalysis analysis;
  double seconds = 0;
};

// The warning of a drifting energy, and the line of one disorder.
void report(const ImpulseSetup& s, const ImpulseAtXi& x) {
  const ImpulseSeries& run = x.series;
  const ImpulseAnalysis& a = x.analysis;
  const double worst_drift = *std::max_element(run.drift.begin(), run.drift.end());
  if (worst_drift > 0.01)
    std::cerr << "warning: xi = " << x.xi << ": the energy of some realization drifted by "
              << 100 * worst_drift << " % (Verlet near the stability limit of its lightest "
              << "beads); a smaller time.dt or a larger disorder.min_mass reduces it\n";
  std::cout << "xi = " << x.xi << ": source keeps " << a.residual / a.energy0 << " of the energy ("
            << a.residual_ratio << " per realization), r^2 ~ t^" << a.exponent
            << ", R - source = " << run.centre.back() - s.source << " (" << x.seconds << " s)\n";
}

// Every disorder's ensemble (rank 0 gets the series and analyses them, a line each as it
// ends; the other ranks run their blocks and get nothing).
std::vector<ImpulseAtXi> run_all(ImpulseSetup& s, bool progress) {
  std::vector<ImpulseAtXi> all;
  for (size_t k = 0; k < s.cs.xis.size(); ++k) {
    WallClock clock;
    ImpulseSeries series = run_xi(s, k, progress);
    if (!ensemble::root()) continue;
    ImpulseAtXi x;
    x.xi = s.cs.xis[k];
    x.series = std::move(series);
    x.seconds = clock.seconds();
    x.analysis = analyse(s, x.series);
    report(s, x);
    all.push_back(std::move(x));
  }
  return all;
}

// Group /xi_<k> of results.h5.
void write_xi_group(H5Writer& h5, size_t k, const ImpulseSetup& s, const ImpulseAtXi& x) {
  const ImpulseSeries& run = x.series;
  const ImpulseAnalysis& a = x.analysis;
  const std::string g = "/xi_" + std::to_string(k);
  // Reduced units (docs/model_chains.md §1), so every unit is "1": time in t_c, energies in
  // F_0 Delta_0 (= m_0 Delta_0^2 / t_c^2), centre and width in bead indices; the source
  // fraction and the drift are ratios.
  write_quantity(h5, g + "/time", run.times, "1");
  write_quantity(h5, g + "/te_mean", run.profile, "1",
                 {static_cast<hsize_t>(s.samples + 1), static_cast<hsize_t>(s.cs.spec.beads)});
  write_quantity(h5, g + "/centre_mean", run.centre, "1");
  write_quantity(h5, g + "/width2_mean", run.width2, "1");
  write_quantity(h5, g + "/source_energy", run.source_energy, "1");
  write_quantity(h5, g + "/source_fraction_per_realization", run.source_ratio, "1");
  write_quantity(h5, g + "/energy_drift", run.drift, "1");
  h5.attribute(g, "xi", x.xi);
  h5.attribute(g, "t_front_far_end", a.t_front);
  h5.attribute(g, "analysis_end_sample", static_cast<double>(a.s_end));
  h5.attribute(g, "near_exponential_rate", a.near_exp.exponent);
  h5.attribute(g, "near_exponential_prefactor", a.near_exp.prefactor);
  h5.attribute(g, "near_beads", static_cast<double>(a.dist.size()));
  h5.attribute(g, "far_beads", static_cast<double>(a.far_end));
  h5.attribute(g, "far_power_law_exponent", a.far_pow.exponent);
  h5.attribute(g, "far_power_law_prefactor", a.far_pow.prefactor);
  h5.attribute(g, "far_exponential_rate", a.far_exp.exponent);
  h5.attribute(g, "far_exponential_prefactor", a.far_exp.prefactor);
}

// The run at one disorder in summary.json (`wall_seconds`: its wall time).
Json run_json(const ImpulseSetup& s, const ImpulseAtXi& x) {
  const ChainScene& cs = s.cs;
  const ImpulseSeries& run = x.series;
  const ImpulseAnalysis& a = x.analysis;
  const double decay_rate = -a.near_exp.exponent;
  Json j = Json::object();
  j["xi"] = x.xi;
  j["analysis_end_time"] = run.times[a.s_end];
  j["source_residual_ratio_of_ensemble_means"] = a.residual / a.energy0;
  j["source_residual_mean_of_realization_fractions"] = a.residual_ratio;
  j["near_source_decay_per_bead"] = Json::or_null(decay_rate);
  j["near_source_beads"] = std::vector<double>{0.0, a.dist.back()};
  j["localization_length_beads"] = decay_rate > 0 ? Json(1.0 / decay_rate) : Json();
  Json far = Json::object();
  far["beads"] = std::vector<double>{1.0, static_cast<double>(a.far_end)};
  far["points"] = static_cast<double>(a.dist_far.size());
  far["power_law_exponent"] = Json::or_null(-a.far_pow.exponent);  // <TE_p> ~ d^-alpha
  far["power_law_exponent_stderr"] = Json::or_null(a.far_pow.exponent_stderr);
  far["power_law_rms_log_residual"] = Json::or_null(a.far_pow.rms_log_residual);
  far["exponential_decay_per_bead"] = Json::or_null(-a.far_exp.exponent);
  far["exponential_rms_log_residual"] = Json::or_null(a.far_exp.rms_log_residual);
  j["decay_over_long_range"] = far;
  j["centre_of_energy_distance_at_t_max"] = run.centre.back() - s.source;
  j["width2_at_t_max"] = run.width2.back();
  j["width2_growth_exponent"] = Json::or_null(a.exponent);  // too few points: undefined
  j["exponent_fit_window"] = std::vector<double>{0.5 * a.t_end, run.times[a.s_end]};
  j["front_reaches_far_end_at"] = a.t_front;
  j["max_relative_energy_drift"] = *std::max_element(run.drift.begin(), run.drift.end());
  j["wall_seconds"] = x.seconds;
  j["solver"] = cs.exact ? "exact" : "verlet";
  if (cs.exact)
    j["seconds_per_realization"] = x.seconds / cs.realizations;
  else
    j["bead_steps_per_second"] = run.bead_steps / x.seconds;
  return j;
}

// results.h5 (a group /xi_<k> per disorder, then the scene's attributes) and summary.json.
void write_results(SceneOutput& output, const ImpulseSetup& s, const std::vector<ImpulseAtXi>& xis,
                   const WallClock& clock) {
  H5Writer& h5 = output.h5();
  Json runs = Json::array();
  std::vector<double> xi_values, residual_means, residual_ratios;
  for (size_t k = 0; k < xis.size(); ++k) {
    const ImpulseAnalysis& a = xis[k].analysis;
    xi_values.push_back(xis[k].xi), residual_means.push_back(a.residual / a.energy0);
    residual_ratios.push_back(a.residual_ratio);
    write_xi_group(h5, k, s, xis[k]);
    runs.push(run_json(s, xis[k]));
  }
  h5.attribute("/", "source", s.source);
  h5.attribute("/", "energy0", 0.5 * s.v0 * s.v0);
  h5.attribute("/", "beads", s.cs.spec.beads);
  Json& summary = output.summary();
  summary["runs"] = runs;
  // Late-time source energy against disorder, a power law over the xi > 0 runs.
  Json against_xi = Json::object();
  against_xi["ratio_of_ensemble_means"] =
      Json::or_null(fit_power_law(xi_values, residual_means).exponent);
  against_xi["mean_of_realization_fractions"] =
      Json::or_null(fit_power_law(xi_values, residual_ratios).exponent);
  summary["source_residual_exponent_vs_xi"] = against_xi;
  summary["wall_seconds"] = clock.seconds();
}

}  // namespace

void run_chain_impulse(const SceneFile& scene, const RunOptions& opts) {
  ImpulseSetup s = read_setup(scene);
  if (!begin_outputs(opts)) return;
  if (!ensemble::root()) {  // rank 0 alone analyses and writes
    run_all(s, opts.progress);
    return;
  }
  SceneOutput output(scene, opts, "chain_impulse");
  output.h5();  // the partial results.h5 made now: an unwritable folder fails before the run
  const WallClock clock;
  const std::vector<ImpulseAtXi> xis = run_all(s, opts.progress);
  write_results(output, s, xis, clock);
  output.finish();
}

}  // namespace granular
