// Chain ensembles: throughput of the batched Verlet sweep (bead-steps per second, Hertz
// and linearized kernels) next to the memory bandwidth measured in the same run; error
// against the exact eigenmode solution versus cost for several time steps; and the cost of
// the master-equation prediction against the full ensemble it replaces.
// Thread count comes from --kokkos-threads; run once per count:
//   bench_chain --kokkos-threads=2 [--realizations 500] [--beads 1024] [--steps 2000]
//               [--reps 5] [--out perf/results/chain_2t.json]
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <iostream>
#include <random>

#include "core/chain/chain_exact.hpp"
#include "core/chain/master_equation.hpp"
#include "kernels/chain/chain_energy.hpp"
#include "machine_info.hpp"

using namespace granular;
using Exec = Kokkos::DefaultExecutionSpace;

namespace {

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

ChainSpec chain(int beads, ChainForce law, double xi) {
  ChainSpec s;
  s.beads = beads, s.force = law, s.xi = xi, s.seed = 2024;
  return s;
}

// Bytes the sweep would move per bead-step if every array came from memory: the contact
// pass reads u and three contact parameters and writes the force; the kick-drift pass
// reads two forces, b, a, v, u and writes a, v, u.
constexpr double kStreamedBytes = 8.0 * (1 + 3 + 1) + 8.0 * (2 + 4 + 3);

// Bytes the on-chip kernel moves per bead-step: each call loads u, v, a, b and the two
// contact parameters once and writes u, v and a once, over all its steps.
double on_chip_bytes(long steps) { return 8.0 * (6 + 3) / static_cast<double>(steps); }

struct Config {
  ChainForce law;
  ChainKernel kernel;
};

// Bead-steps per second of each law with each kernel, repetitions interleaved; a kernel
// that cannot hold the chain on this space gets a row saying so instead of a figure.
Json throughput(int R, int N, long steps, int reps) {
  const std::vector<Config> configs = {{ChainForce::Hertz, ChainKernel::Global},
                                       {ChainForce::Linear, ChainKernel::Global},
                                       {ChainForce::Hertz, ChainKernel::OnChip},
                                       {ChainForce::Linear, ChainKernel::OnChip}};
  std::vector<std::vector<double>> rates(configs.size());
  std::vector<std::string> refused(configs.size());
  std::vector<ChainBatch<Exec>> batches;
  for (std::size_t k = 0; k < configs.size(); ++k) {
    batches.emplace_back(chain(N, configs[k].law, 0.1), ChainBatch<Exec>::first(R));
    batches.back().kernel = configs[k].kernel;
    chain_set_impulse(batches.back(), 0, 0.01);
    chain_accelerations(batches.back());
    try {
      chain_advance(batches.back(), 0.1, 100);  // warm-up
    } catch (const InputError& e) {
      refused[k] = e.what();
    }
  }
  for (int rep = 0; rep < reps; ++rep)
    for (std::size_t k = 0; k < configs.size(); ++k) {  // interleaved repetitions
      if (!refused[k].empty()) continue;
      Kokkos::fence();
      Kokkos::Timer t;
      chain_advance(batches[k], 0.1, steps);
      Kokkos::fence();
      rates[k].push_back(double(R) * N * steps / t.seconds());
    }
  Json rows = Json::array();
  for (std::size_t k = 0; k < configs.size(); ++k) {
    const bool chip = configs[k].kernel == ChainKernel::OnChip;
    Json row = Json::object();
    row["law"] = configs[k].law == ChainForce::Hertz ? "hertz" : "linear";
    row["kernel"] = chip ? "on_chip" : "global";
    row["realizations"] = R;
    row["beads"] = N;
    row["steps"] = steps;
    if (!refused[k].empty()) {
      row["refused"] = refused[k];
      rows.push(row);
      continue;
    }
    const double bytes = chip ? on_chip_bytes(steps) : kStreamedBytes;
    row["bead_steps_per_second"] = rates[k];
    row["median_bead_steps_per_second"] = median_of(rates[k]);
    row["streamed_bytes_per_bead_step"] = bytes;
    row["effective_bandwidth_GBs"] = median_of(rates[k]) * bytes / 1e9;
    rows.push(row);
  }
  // Both kernels must agree to the bit: the benchmark refuses to report a kernel that
  // does not (the same start, the same number of steps).
  for (std::size_t k = 2; k < configs.size(); ++k)
    if (refused[k].empty() && refused[k - 2].empty()) {
      auto a = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), batches[k].u);
      auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), batches[k - 2].u);
      for (std::size_t i = 0; i < a.size(); ++i)
        if (a.data()[i] != b.data()[i])
          throw std::runtime_error("on-chip and global chain kernels disagree");
    }
  return rows;
}

// Verlet (linearized and Hertz kernels) against the exact linearized solution after
// t_end: relative displacement error and largest relative energy error, with the cost.
Json error_vs_cost(int N, int R, double t_end) {
  Json rows = Json::array();
  const std::vector<double> dts = {0.6, 0.4, 0.2, 0.1, 0.05, 0.025, 0.0125};
  for (auto law : {ChainForce::Linear, ChainForce::Hertz})
    for (double dt : dts) {
      ChainBatch<Exec> c(chain(N, law, 0.1), ChainBatch<Exec>::first(R));
      chain_set_impulse(c, 0, 0.01);
      chain_accelerations(c);
      const auto e0 = chain_totals(c);
      const long steps = std::lround(t_end / dt);
      Kokkos::fence();
      Kokkos::Timer timer;
      chain_advance(c, dt, steps);
      Kokkos::fence();
      const double seconds = timer.seconds();
      const auto e1 = chain_totals(c);
      auto hu = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.u);
      auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.b);
      auto hk = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.klin);
      double err = 0, energy_err = 0;
      const int checked = std::min(R, 4);  // exact solutions are O(N^3) each
      for (int r = 0; r < checked; ++r) {
        ChainExactSolution ex(std::vector<double>(&hb(r, 0), &hb(r, 0) + N),
                              std::vector<double>(&hk(r, 0), &hk(r, 0) + c.C), false);
        Eigen::VectorXd u0 = Eigen::VectorXd::Zero(N), v0 = Eigen::VectorXd::Zero(N), u, v;
        v0(0) = 0.01;
        ex.set_initial(u0, v0);
        ex.state(c.time, u, v);
        Eigen::VectorXd num(N);
        for (int i = 0; i < N; ++i) num(i) = hu(r, i);
        err = std::max(err, (num - u).norm() / u.norm());
        const auto& a = law == ChainForce::Hertz ? e0.hertz : e0.linear;
        const auto& b = law == ChainForce::Hertz ? e1.hertz : e1.linear;
        energy_err = std::max(energy_err, std::abs(b[r] / a[r] - 1));
      }
      Json row = Json::object();
      row["kernel"] = law == ChainForce::Hertz ? "hertz" : "linear";
      row["dt"] = dt;
      row["dt_over_stability_limit"] = dt / (2.0 / (2.0 * std::sqrt(1.5)));
      row["relative_displacement_error"] = err;
      row["relative_energy_error"] = energy_err;
      row["seconds_per_unit_time_per_realization"] = seconds / t_end / R;
      rows.push(row);
      std::cout << "error vs cost: " << (law == ChainForce::Hertz ? "hertz " : "linear") << " dt "
                << dt << " error " << err << " energy " << energy_err << "\n";
    }
  return rows;
}

// The validation experiment of chain_master_equation (N + 1 = 256, 32 bands, 100
// realizations, 80 time units sampled every 1) against its master-equation prediction.
Json master_equation_cost() {
  const int B = 32, R = 100, T = 80;
  ChainSpec s = chain(255, ChainForce::Hertz, 0.1);
  ChainBatch<Exec> c(s, ChainBatch<Exec>::first(R));
  std::vector<int> tones;
  for (int r = 0; r < R; ++r)
    tones.push_back(chain_band_tone(6, 256, B)), tones.push_back(chain_band_tone(20, 256, B));
  chain_set_standing_waves(c, tones, 2, 0.01);
  chain_accelerations(c);
  ChainSpectrum spectrum(R, chain_lattice(s));
  std::vector<double> times;
  Kokkos::Timer t;
  for (int i = 0; i <= T; ++i) {
    if (i > 0) chain_advance(c, 0.05, 20);
    chain_spectrum(spectrum, c);
    chain_band_energies(spectrum.bins(), R, 256, B);
    times.push_back(c.time);
  }
  const double ensemble = t.seconds();
  // A balanced random transfer matrix of the measured magnitude.
  std::mt19937_64 gen(1);
  std::uniform_real_distribution<double> U(0, 0.01);
  Eigen::MatrixXd Q(B, B);
  for (int i = 0; i < B; ++i)
    for (int j = 0; j < B; ++j) Q(i, j) = U(gen);
  Q = balance_columns(Q);
  Kokkos::Timer t2;
  const auto e = solve_master_equation(Q, Eigen::VectorXd::Unit(B, 6), times);
  const double me = t2.seconds();
  Json row = Json::object();
  row["ensemble_seconds"] = ensemble;
  row["master_equation_seconds"] = me;
  row["speedup"] = ensemble / me;
  row["check_sum"] = e.col(T).sum();  // stays 1: the prediction conserves energy
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::initialize(argc, argv);
  int rc = 0;
  try {
    int R = 500, N = 1024, reps = 5;
    long steps = 2000;
    std::string out;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw std::runtime_error("missing value after " + a);
        return argv[++i];
      };
      if (a == "--realizations")
        R = std::stoi(next());
      else if (a == "--beads")
        N = std::stoi(next());
      else if (a == "--steps")
        steps = std::stol(next());
      else if (a == "--reps")
        reps = std::stoi(next());
      else if (a == "--out")
        out = next();
      else if (a.rfind("--kokkos", 0) != 0)
        throw std::runtime_error("unknown option " + a);
    }
    const int threads = Exec::concurrency();
    if (out.empty()) out = "perf/results/chain_" + std::to_string(threads) + "t.json";
    Json result = Json::object();
    result["benchmark"] = "chain";
    result["machine"] = perf::machine_info();
    const double bw = perf::triad_bandwidth();
    result["triad_bandwidth_GBs"] = bw / 1e9;
    result["throughput"] = throughput(R, N, steps, reps);
    result["error_vs_cost"] = error_vs_cost(256, 16, 100.0);
    result["master_equation_cost"] = master_equation_cost();
    write_text_file(out, result.dump());
    std::cout << "triad " << bw / 1e9 << " GB/s; results in " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    rc = 1;
  }
  Kokkos::finalize();
  return rc;
}
