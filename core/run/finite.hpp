// Failures must not vanish into a result: std::max(x, NaN) returns x and drops the NaN, so a
// largest error over failed cases would read 0. These helpers keep a NaN once it appears,
// and name the quantity that was not finite.
#pragma once
#include <cmath>
#include <sstream>
#include <string>

#include "core/run/error.hpp"

namespace granular {

// max(a, b) that returns NaN when either is NaN.
inline double max_keep_nan(double a, double b) {
  return std::isnan(a) || std::isnan(b) ? std::nan("") : (a < b ? b : a);
}

// Stops the run (PhysicsError) when v is NaN or inf, naming what it is and where.
inline void require_finite(double v, const std::string& what, long step, double time) {
  if (std::isfinite(v)) return;
  std::ostringstream msg;
  msg.precision(6);
  msg << "non-finite " << what << " (" << v << ") at step " << step << " (t = " << time
      << "): the integration failed; reduce the time step, or report the scene if it persists";
  throw PhysicsError(msg.str());
}

}  // namespace granular
