// Travel-time pickers for a received pulse: first arrival (the signal leaves a noise band
// estimated from a pre-arrival window), first peak and first trough (the first local
// extremum of each sign beyond that band). Times are interpolated between samples: linear
// for the threshold crossing, a parabola through three samples for the extrema.
#pragma once
#include "core/signal/trace.hpp"

namespace granular {

struct PickerOptions {
  // Samples with t < noise_end form the pre-arrival window: its mean is the baseline and
  // its RMS deviation the noise level. With no sample in it the baseline is 0 and the noise 0.
  double noise_end = 0.0;
  double noise_factor = 5.0;         // threshold = max(noise_factor x noise RMS, ...
  double relative_threshold = 0.02;  // ... relative_threshold x largest |a - baseline|)
  double search_start = -1e300;      // arrivals before this time are ignored (e.g. crosstalk)
};

struct Picks {
  double baseline = 0, noise_rms = 0, threshold = 0;
  double first_arrival = NAN, first_peak = NAN, first_trough = NAN;  // NAN: not found
  double peak_amplitude = NAN, trough_amplitude = NAN;               // relative to baseline
  int arrival_index = -1, peak_index = -1, trough_index = -1;        // nearest sample
};

// Polarity: a peak is a maximum of a - baseline above +threshold, a trough a minimum below
// -threshold; the first arrival is where |a - baseline| first exceeds the threshold.
Picks pick_travel_times(const Trace& trace, const PickerOptions& options);

}  // namespace granular
