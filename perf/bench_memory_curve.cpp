// The machine's own memory curve: triad bandwidth (a = b + 3 c, 24 bytes per element) against
// the working set, from arrays that fit the first-level cache to arrays far beyond the last.
// A step whose work per particle is the same at every N (perf/peer/run_flatness_sweep.sh
// times such steps on tiled packings) can fall with N only as far as its memory traffic
// meets this curve.
//
//   bench_memory_curve --kokkos-threads=1 [--out perf/results/memory_curve_1t.json]
//                      [--min-kib 64] [--max-mib 512]
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <iostream>
#include <stdexcept>
#include <string>

#include "core/io/output.hpp"
#include "machine_info.hpp"

using namespace granular;

int main(int argc, char** argv) {
  Kokkos::initialize(argc, argv);
  int rc = 0;
  {
    std::string out;
    long min_kib = 64, max_mib = 512;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if ((a == "--out" || a == "--min-kib" || a == "--max-mib") && i + 1 >= argc) {
        std::cerr << "missing value after " << a << "\n";
        rc = 2;
        break;
      }
      if (a == "--out")
        out = argv[++i];
      else if (a == "--min-kib" || a == "--max-mib") {
        const std::string value = argv[++i];
        try {
          size_t used = 0;
          (a == "--min-kib" ? min_kib : max_mib) = std::stol(value, &used);
          if (used != value.size()) throw std::invalid_argument(value);
        } catch (const std::exception&) {
          std::cerr << a << " takes a whole number, not '" << value << "'\n";
          rc = 2;
          break;
        }
      } else if (a.rfind("--kokkos", 0) != 0) {
        std::cerr << "unknown option " << a << "\n";
        rc = 2;
        break;
      }
    }
    if (rc == 0 && (min_kib < 1 || max_mib < 1 || min_kib > 1024 * max_mib)) {
      std::cerr << "need 1 <= --min-kib <= 1024 x --max-mib\n";
      rc = 2;
    }
    if (rc == 0) {
      const int threads = Kokkos::DefaultExecutionSpace::concurrency();
      if (out.empty()) out = "perf/results/memory_curve_" + std::to_string(threads) + "t.json";
      Json result = Json::object();
      result["benchmark"] = "memory_curve";
      result["machine"] = perf::machine_info();
      result["kernel"] = "triad a = b + 3 c; bytes = 24 per element (three arrays); best of reps";
      Json rows = Json::array();
      // Four points per doubling of the working set; each size repeated until ~2 GB has
      // moved (at least 5 times), so the small sizes are timed over many passes.
      for (double kib = static_cast<double>(min_kib); kib <= 1024.0 * max_mib * 1.0001;
           kib *= 1.189207115) {
        const long n = static_cast<long>(kib * 1024 / 24);
        const int reps = static_cast<int>(std::max(5.0, std::min(20000.0, 2e9 / (24.0 * n))));
        const double bw = perf::triad_bandwidth(n, reps);
        Json row = Json::object();
        row["working_set_bytes"] = 24.0 * n;
        row["bandwidth_GBs"] = bw / 1e9;
        rows.push(row);
        std::cout << "working set " << 24.0 * n / 1048576 << " MiB: " << bw / 1e9 << " GB/s\n";
      }
      result["rows"] = rows;
      try {
        write_text_file(out, result.dump());
        std::cout << "wrote " << out << "\n";
      } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        rc = 1;
      }
    }
  }
  Kokkos::finalize();
  return rc;
}
