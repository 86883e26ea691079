// Wall seconds per kernel and per phase of a run (`granular run --kernel-times`, docs/speed.md):
// Kokkos Tools callbacks time every parallel dispatch from its begin to its end and file it
// under the phase that is open, a region a driver names with KernelRegion. On the host
// backends a dispatch returns once its work is done, so that span is the kernel's time; on
// a device a launch returns early, so the timer fences at the end of each kernel there (which
// serialises launches: the breakdown is right, the total a little slower than a plain run).
// Off, the regions cost one branch each and the kernels nothing.
#pragma once
#include <string>
#include <vector>

#include "core/io/output.hpp"

namespace granular {

namespace kernel_times {

struct Kernel {
  std::string name;
  long calls = 0;
  double seconds = 0;
};

struct Region {
  std::string name;  // nested regions as "outer / inner"; "" outside any region
  long entries = 0;
  double wall_seconds = 0;      // from each opening to its closing (0 for "")
  std::vector<Kernel> kernels;  // in the order first seen
};

// Installs the callbacks and clears the tables. `fence`: fence after every kernel (default:
// where the default execution space is not on the host).
void start();
void start(bool fence);
// Removes the callbacks; the tables stay readable.
void stop();
bool running();
std::vector<Region> regions();  // in the order first opened
// {"regions": [{"name", "entries", "wall_seconds", "kernel_seconds", "kernels": [{"name",
//  "calls", "seconds"}] sorted by seconds, largest first}]}
Json json();

}  // namespace kernel_times

// A named phase of a run for the kernel timer; nothing when the timer is off.
class KernelRegion {
 public:
  explicit KernelRegion(const std::string& name);
  ~KernelRegion();
  KernelRegion(const KernelRegion&) = delete;
  KernelRegion& operator=(const KernelRegion&) = delete;

 private:
  bool open_;
};

}  // namespace granular
