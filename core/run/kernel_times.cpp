// Kernel timer over Kokkos Tools callbacks (see kernel_times.hpp).
#include "core/run/kernel_times.hpp"

#include <Kokkos_Core.hpp>
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <type_traits>
#include <unordered_map>

namespace granular {

namespace kernel_times {

namespace {

using Clock = std::chrono::steady_clock;

// Dispatches come from the thread that drives the run, one at a time (a kernel launches no
// kernel), so one open kernel and one region stack suffice.
struct State {
  bool running = false, fence = false;
  std::vector<Region> regions;
  std::unordered_map<std::string, size_t> region_index;
  std::vector<std::unordered_map<std::string, size_t>> kernel_index;  // per region
  std::vector<size_t> stack;                // open regions (indices), innermost last
  std::vector<Clock::time_point> opened;    // when each open region was opened
  size_t current = 0;                       // the innermost open region ("" at the bottom)
  size_t open_region = 0, open_kernel = 0;  // the running kernel
  Clock::time_point kernel_start;
};

State& state() {
  static State s;
  return s;
}

size_t region_named(const std::string& name) {
  State& s = state();
  auto it = s.region_index.find(name);
  if (it != s.region_index.end()) return it->second;
  s.regions.push_back(Region{name, 0, 0.0, {}});
  s.kernel_index.emplace_back();
  s.region_index.emplace(name, s.regions.size() - 1);
  return s.regions.size() - 1;
}

void begin_kernel(const char* name, uint32_t, uint64_t* id) {
  State& s = state();
  auto& index = s.kernel_index[s.current];
  auto it = index.find(name);
  if (it == index.end()) {
    s.regions[s.current].kernels.push_back(Kernel{name, 0, 0.0});
    it = index.emplace(name, s.regions[s.current].kernels.size() - 1).first;
  }
  s.open_region = s.current, s.open_kernel = it->second;
  *id = it->second;
  s.kernel_start = Clock::now();
}

void end_kernel(uint64_t) {
  State& s = state();
  if (s.fence) Kokkos::fence();
  Kernel& k = s.regions[s.open_region].kernels[s.open_kernel];
  k.seconds += std::chrono::duration<double>(Clock::now() - s.kernel_start).count();
  ++k.calls;
}

void push_region(const char* name) {
  State& s = state();
  const std::string path =
      s.stack.empty() ? std::string(name) : s.regions[s.current].name + " / " + name;
  s.current = region_named(path);
  ++s.regions[s.current].entries;
  s.stack.push_back(s.current);
  s.opened.push_back(Clock::now());
}

void pop_region() {
  State& s = state();
  if (s.stack.empty()) return;  // a region opened before the timer started
  if (s.fence) Kokkos::fence();
  s.regions[s.stack.back()].wall_seconds +=
      std::chrono::duration<double>(Clock::now() - s.opened.back()).count();
  s.stack.pop_back(), s.opened.pop_back();
  s.current = s.stack.empty() ? region_named("") : s.stack.back();
}

void set_callbacks(bool on) {
  using namespace Kokkos::Tools::Experimental;
  set_begin_parallel_for_callback(on ? begin_kernel : nullptr);
  set_begin_parallel_reduce_callback(on ? begin_kernel : nullptr);
  set_begin_parallel_scan_callback(on ? begin_kernel : nullptr);
  set_end_parallel_for_callback(on ? end_kernel : nullptr);
  set_end_parallel_reduce_callback(on ? end_kernel : nullptr);
  set_end_parallel_scan_callback(on ? end_kernel : nullptr);
  set_push_region_callback(on ? push_region : nullptr);
  set_pop_region_callback(on ? pop_region : nullptr);
}

}  // namespace

void start() {
  start(!std::is_same_v<Kokkos::DefaultExecutionSpace::memory_space, Kokkos::HostSpace>);
}

void start(bool fence) {
  State& s = state();
  s = State();
  s.fence = fence;
  s.current = region_named("");
  set_callbacks(true);
  s.running = true;
}

void stop() {
  if (!running()) return;
  set_callbacks(false);
  state().running = false;
}

bool running() { return state().running; }

std::vector<Region> regions() { return state().regions; }

Json json() {
  Json rows = Json::array();
  for (Region r : regions()) {
    if (r.name.empty() && r.kernels.empty()) continue;
    std::stable_sort(r.kernels.begin(), r.kernels.end(),
                     [](const Kernel& a, const Kernel& b) { return a.seconds > b.seconds; });
    Json kernels = Json::array();
    double total = 0;
    for (const Kernel& k : r.kernels) {
      Json row = Json::object();
      row["name"] = k.name, row["calls"] = k.calls, row["seconds"] = k.seconds;
      kernels.push(row);
      total += k.seconds;
    }
    Json row = Json::object();
    row["name"] = r.name.empty() ? "(outside any region)" : r.name;
    row["entries"] = r.entries;
    row["wall_seconds"] = r.wall_seconds;
    row["kernel_seconds"] = total;
    row["kernels"] = kernels;
    rows.push(row);
  }
  Json out = Json::object();
  out["fenced"] = state().fence;
  out["regions"] = rows;
  return out;
}

}  // namespace kernel_times

KernelRegion::KernelRegion(const std::string& name) : open_(kernel_times::running()) {
  if (open_) Kokkos::Profiling::pushRegion(name);
}

KernelRegion::~KernelRegion() {
  if (open_ && kernel_times::running()) Kokkos::Profiling::popRegion();
}

}  // namespace granular
