// Facts about the machine and build that every benchmark result file records, and a
// STREAM-like triad that measures the sustainable memory bandwidth in the same run.
#pragma once
#include <Kokkos_Core.hpp>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include "core/io/output.hpp"

namespace granular::perf {

inline std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

// Peak resident set size of this process (VmHWM of /proc/self/status) in kB; -1 if unknown.
inline long peak_resident_kB() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

inline Json machine_info() {
  Json m = Json::object();
  m["cpu_model"] = cpu_model();
  m["hardware_threads"] = static_cast<int>(std::thread::hardware_concurrency());
  m["compiler"] = std::string(__VERSION__);
  m["kokkos_execution_space"] = std::string(Kokkos::DefaultExecutionSpace::name());
  m["kokkos_concurrency"] = Kokkos::DefaultExecutionSpace::concurrency();
  const char* bind = std::getenv("OMP_PROC_BIND");
  m["OMP_PROC_BIND"] = bind ? bind : "unset";
  m["resident_kB"] = peak_resident_kB();  // peak so far, at the time of the call
  return m;
}

// Triad a = b + s c over arrays far larger than the last-level cache; returns the best
// of `reps` in bytes per second (24 bytes per element: two reads, one write; write-allocate
// traffic is not counted, as in STREAM).
inline double triad_bandwidth(long n = 1L << 25, int reps = 10) {
  using Exec = Kokkos::DefaultExecutionSpace;
  Kokkos::View<double*> a("triad::a", n), b("triad::b", n), c("triad::c", n);
  Kokkos::deep_copy(b, 1.0);
  Kokkos::deep_copy(c, 2.0);
  double best = 0;
  for (int r = 0; r < reps; ++r) {
    Kokkos::fence();
    Kokkos::Timer t;
    Kokkos::parallel_for(
        "perf::triad", Kokkos::RangePolicy<Exec>(0, n),
        KOKKOS_LAMBDA(const long i) { a(i) = b(i) + 3.0 * c(i); });
    Kokkos::fence();
    best = std::max(best, 24.0 * n / t.seconds());
  }
  return best;
}

// Copy bandwidth (bytes read plus written) of the backend's own array copy, best of `reps`:
// on a GPU a device-to-device memcpy, which reaches more of the memory's bandwidth than the
// triad kernel above (2.48 TB/s on both an H100 and an H200 for the triad, whose memories
// differ by 1.4x: the triad kernel, not the memory, sets that figure there).
inline double copy_bandwidth(long n = 1L << 25, int reps = 10) {
  Kokkos::View<double*> a("copy::a", n), b("copy::b", n);
  Kokkos::deep_copy(b, 1.0);
  double best = 0;
  for (int r = 0; r < reps; ++r) {
    Kokkos::fence();
    Kokkos::Timer t;
    Kokkos::deep_copy(a, b);
    Kokkos::fence();
    best = std::max(best, 16.0 * n / t.seconds());
  }
  return best;
}

}  // namespace granular::perf
