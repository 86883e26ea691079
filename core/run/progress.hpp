// Progress of long runs: phase, step, rate and ETA, redrawn in place on a terminal and
// printed at every tenth of the phase otherwise (logs stay short). Each phase also keeps to
// the run's wall-time budget: one projected, at the rate measured on this machine, to last
// longer than the budget stops with that estimate (PhysicsError), whether or not progress
// lines are shown.
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

  // The budget of every phase, in hours (0: none; `granular run --max-hours`).
  static void set_budget_hours(double hours);
  static double budget_hours();
  // Whether a phase at `step` of `total` after `elapsed` seconds is projected past `budget`
  // seconds. Judged once the rate is measured: after the shorter of 30 s and a tenth of the
  // budget, and at least one step.
  static bool over_budget(double elapsed, long step, long total, double budget);

 private:
  std::string phase_;
  long total_;
  bool enabled_, tty_, done_ = false;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace granular
