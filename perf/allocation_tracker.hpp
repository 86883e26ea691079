// High-water mark of every Kokkos allocation, by memory space and View label, taken through
// Kokkos' tools interface (the allocate/deallocate callbacks every View allocation calls).
// Used by the throughput benchmark to report the bytes per particle a system holds on the
// device at its peak, array by array (docs/gpu_memory.md).
//
// Installing the callbacks makes Kokkos believe a tool is loaded: each kernel launch then
// also builds its name (a string), which costs well under a microsecond per launch. The
// benchmark therefore tracks its first repetition only and times the others untracked.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace granular::perf {

class AllocationTracker {
 public:
  struct Entry {
    std::string space, label;
    double bytes = 0;
  };

  // Starts counting from zero (allocations made before stay uncounted, and so do their frees).
  static void start() {
    State& s = state();
    std::lock_guard<std::mutex> lock(s.mutex);
    s.live.clear();
    s.by_key.clear();
    s.at_peak.clear();
    s.current = s.peak = 0;
    Kokkos::Tools::Experimental::set_allocate_data_callback(&on_allocate);
    Kokkos::Tools::Experimental::set_deallocate_data_callback(&on_deallocate);
  }
  static void stop() {
    Kokkos::Tools::Experimental::set_allocate_data_callback(nullptr);
    Kokkos::Tools::Experimental::set_deallocate_data_callback(nullptr);
  }

  // Peak of the bytes live at once in memory spaces whose name does not start with "Host"
  // (on a host backend every space is a host space: then all of them).
  static double peak_bytes() { return state().peak; }

  // The live allocations at that peak, summed by (space, label), largest first.
  static std::vector<Entry> breakdown_at_peak() {
    State& s = state();
    std::lock_guard<std::mutex> lock(s.mutex);
    std::vector<Entry> out;
    for (const auto& [key, bytes] : s.at_peak)
      if (bytes > 0) out.push_back({key.first, key.second, bytes});
    std::sort(out.begin(), out.end(),
              [](const Entry& a, const Entry& b) { return a.bytes > b.bytes; });
    return out;
  }

 private:
  using Key = std::pair<std::string, std::string>;  // (space, label)
  struct State {
    std::mutex mutex;
    std::map<const void*, std::pair<Key, std::uint64_t>> live;
    std::map<Key, double> by_key;
    std::map<Key, double> at_peak;
    double current = 0, peak = 0;
  };
  static State& state() {
    static State s;
    return s;
  }
  static bool counted(const std::string& space) {
    // A device backend's host mirrors are not device memory; on a host backend they are all
    // there is.
    return std::string(Kokkos::DefaultExecutionSpace::memory_space::name()).rfind("Host", 0) == 0 ||
           space.rfind("Host", 0) != 0;
  }
  static void on_allocate(const Kokkos_Profiling_SpaceHandle handle, const char* label,
                          const void* ptr, const std::uint64_t size) {
    State& s = state();
    const std::string space = handle.name;
    if (!counted(space)) return;
    std::lock_guard<std::mutex> lock(s.mutex);
    const Key key{space, label ? label : ""};
    s.live[ptr] = {key, size};
    s.by_key[key] += static_cast<double>(size);
    s.current += static_cast<double>(size);
    if (s.current > s.peak) {
      s.peak = s.current;
      s.at_peak = s.by_key;
    }
  }
  static void on_deallocate(const Kokkos_Profiling_SpaceHandle, const char*, const void* ptr,
                            const std::uint64_t) {
    State& s = state();
    std::lock_guard<std::mutex> lock(s.mutex);
    const auto it = s.live.find(ptr);
    if (it == s.live.end()) return;  // allocated before start(), or not a counted space
    s.by_key[it->second.first] -= static_cast<double>(it->second.second);
    s.current -= static_cast<double>(it->second.second);
    s.live.erase(it);
  }
};

}  // namespace granular::perf
