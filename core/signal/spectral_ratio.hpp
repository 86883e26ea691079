// Spectral-ratio attenuation: for the same pulse received after travel times t1 < t2,
// A2(f) = A1(f) G exp(-pi f (t2 - t1)/Q) with a frequency-independent factor G (geometry,
// coupling), so ln|A2/A1| = ln G + m f with slope m = -pi (t2 - t1)/Q. The slope is fitted by
// least squares over a frequency band; Q = -pi (t2 - t1)/m and 1/Q with their standard errors.
// (The source writes ln|A1/A2| with the same slope formula, docs/model_mixtures_and_waves.md
// §4; with t2 > t1 that gives Q < 0 for an attenuating medium, so the ratio taken here is
// A2/A1.)
#pragma once
#include "core/signal/spectrum.hpp"

namespace granular {

struct SpectralRatioFit {
  double f_lo = 0, f_hi = 0, delay = 0;
  int points = 0;
  double slope = 0, intercept = 0, slope_error = 0, r2 = 0;
  double q = 0, inv_q = 0, inv_q_error = 0, q_error = 0;
  std::vector<double> f, log_ratio;  // the fitted points
};

// Fits ln(A2/A1) over bins with f_lo <= f <= f_hi (f > 0) where both amplitudes are positive.
// The spectra must share their frequency grid (same dt and nfft). delay = t2 - t1 > 0.
SpectralRatioFit spectral_ratio(const Spectrum& s1, const Spectrum& s2, double delay, double f_lo,
                                double f_hi);

// The usable band of two spectra: the bins around the first spectrum's largest amplitude at
// f > 0 where both amplitudes stay above `fraction` of their own maxima.
void common_band(const Spectrum& s1, const Spectrum& s2, double fraction, double& f_lo,
                 double& f_hi);

}  // namespace granular
