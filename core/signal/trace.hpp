// A sampled time series (a transducer or receiver signal): times and amplitudes, uniformly
// sampled. The signal-analysis code (pickers, spectra, spectral ratio) works on these, so it
// runs on engine signals and laboratory traces alike.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "core/run/error.hpp"

namespace granular {

struct Trace {
  std::vector<double> t, a;

  int size() const { return static_cast<int>(t.size()); }
  double step() const { return t.size() > 1 ? (t.back() - t.front()) / (t.size() - 1) : 0.0; }

  // Throws naming `what` unless the trace has at least `min_samples` samples, as many
  // amplitudes as times, finite values and a uniform sampling interval (to 1e-6 of it: the
  // FFT and the pickers' interpolation assume one).
  void validate(const std::string& what, int min_samples = 8) const {
    if (t.size() != a.size())
      throw InputError(what + ": " + std::to_string(t.size()) + " times but " +
                       std::to_string(a.size()) + " amplitudes");
    if (size() < min_samples)
      throw InputError(what + ": needs at least " + std::to_string(min_samples) + " samples, has " +
                       std::to_string(size()));
    const double h = step();
    if (!(h > 0)) throw InputError(what + ": times must increase");
    for (int i = 0; i < size(); ++i) {
      if (!std::isfinite(t[i]) || !std::isfinite(a[i]))
        throw InputError(what + ": sample " + std::to_string(i) + " is not finite");
      if (i > 0 && std::abs(t[i] - t[i - 1] - h) > 1e-6 * h)
        throw InputError(what + ": sampling is not uniform at sample " + std::to_string(i) +
                         " (interval " + std::to_string(t[i] - t[i - 1]) + " against the mean " +
                         std::to_string(h) + ")");
    }
  }
};

}  // namespace granular
