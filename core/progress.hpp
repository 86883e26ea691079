// Progress of long runs: phase, step, rate and ETA, redrawn in place on a terminal and
// printed at every tenth of the phase otherwise (logs stay short).
#pragma once
#include <chrono>
#include <string>

namespace granular {

class Progress {
 public:
  Progress(std::string phase, long total_steps, bool enabled = true);
  ~Progress();
  void update(long step, const std::string& extra = "");
  void finish();
  bool enabled() const { return enabled_; }

 private:
  std::string phase_;
  long total_;
  bool enabled_, tty_, done_ = false;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace granular
