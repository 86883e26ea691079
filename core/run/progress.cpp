// Terminal progress (see progress.hpp).
#include "core/run/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "core/run/ensemble.hpp"
#include "core/run/error.hpp"

namespace granular {

namespace {
double budget_seconds = 72 * 3600.0;
}

void Progress::set_budget_hours(double hours) { budget_seconds = hours * 3600.0; }
double Progress::budget_hours() { return budget_seconds / 3600.0; }

bool Progress::over_budget(double elapsed, long step, long total, double budget) {
  if (!(budget > 0) || step < 1 || elapsed < std::min(30.0, 0.1 * budget)) return false;
  return elapsed * static_cast<double>(total) / static_cast<double>(step) > budget;
}

Progress::Progress(std::string phase, long total_steps, bool enabled)
    : phase_(ensemble::prefix() + std::move(phase)),
      total_(total_steps > 0 ? total_steps : 1),
      enabled_(enabled),
      // Ranks share one terminal: lines, not a line redrawn in place.
      tty_(isatty(fileno(stderr)) != 0 && ensemble::size() == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(long step, const std::string& extra) {
  if (done_) return;
  const auto now = std::chrono::steady_clock::now();
  const double spent = std::chrono::duration<double>(now - start_).count();
  if (over_budget(spent, step, total_, budget_seconds)) {
    done_ = true;
    std::ostringstream m;
    m.precision(3);
    m << "phase '" << phase_ << "' is projected to take " << spent * total_ / step / 3600.0
      << " h on this machine (step " << step << " of " << total_ << " after " << spent
      << " s), beyond the run's budget of " << budget_seconds / 3600.0
      << " h: shorten the phase (its duration or step count in the scene file), or raise "
         "--max-hours (0: no limit)";
    throw PhysicsError(m.str());
  }
  if (!enabled_) return;
  const int decile = static_cast<int>(10 * step / total_);
  if (tty_) {
    if (now - last_draw_ < std::chrono::milliseconds(250) && step < total_) return;
  } else if (decile == last_decile_) {
    return;
  }
  last_draw_ = now;
  last_decile_ = decile;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double eta = step > 0 ? elapsed * (total_ - step) / step : 0.0;
  std::fprintf(stderr, "%s[%s] step %ld/%ld (%3.0f%%) elapsed %.0fs ETA %.0fs %s%s",
               tty_ ? "\r\033[K" : "", phase_.c_str(), step, total_, 100.0 * step / total_, elapsed,
               eta, extra.c_str(), tty_ ? "" : "\n");
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || done_) return;
  done_ = true;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s[%s] done in %.1fs\n", tty_ ? "\r\033[K" : "", phase_.c_str(), elapsed);
}

}  // namespace granular
