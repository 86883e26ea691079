// Signal analysis on synthetic signals whose answers are known in closed form: the pickers
// against the exact threshold crossing, peak and trough of analytic pulses; the FFT energy
// spectrum against Parseval and the Ricker spectrum's peak frequency; the spectral-ratio
// estimator against the Q used to attenuate a wavelet (Kolsky-Futterman constant Q).
#include <gtest/gtest.h>

#include <cmath>

#include "core/signal/signal_pickers.hpp"
#include "core/signal/spectral_ratio.hpp"
#include "core/signal/spectrum.hpp"
#include "core/signal/synthetic_signals.hpp"

using namespace granular;

namespace {

// Ricker source of peak frequency 1 at t = 2, 4096 samples at dt = 0.01.
Trace ricker_source() { return sample_trace(4096, 0.01, ricker, 1.0, 2.0); }

}  // namespace

TEST(SignalPickers, FirstArrivalIsTheExactThresholdCrossingOfARaisedCosine) {
  const double dt = 0.01, T = 2.0, t0 = 3.1234;
  const Trace tr = sample_trace(1000, dt, raised_cosine, T, t0);
  PickerOptions o;
  o.noise_end = 2.0, o.relative_threshold = 0.05;
  const Picks p = pick_travel_times(tr, o);
  EXPECT_EQ(p.noise_rms, 0.0);
  // (1 - cos(2 pi tau/T))/2 = r  <=>  tau = T/(2 pi) acos(1 - 2r); the largest sample is
  // within dt of the peak 1, so the threshold is 0.05 x that sample.
  const double r = p.threshold;
  EXPECT_NEAR(r, 0.05, 0.05 * 1e-4);
  const double exact = t0 + T / (2 * M_PI) * std::acos(1 - 2 * r);
  // Linear interpolation on a curve of curvature a'' over one sample: error <= a'' dt^2/(8 a')
  const double a1 = M_PI / T * std::sin(2 * M_PI * (exact - t0) / T);
  const double a2 = 2 * M_PI * M_PI / (T * T);
  EXPECT_NEAR(p.first_arrival, exact, a2 * dt * dt / (8 * a1));
  EXPECT_NEAR(p.first_peak, t0 + T / 2, 1e-6);  // a cosine is a parabola to O(dt^4)
  EXPECT_TRUE(std::isnan(p.first_trough));      // a one-signed pulse has none
}

TEST(SignalPickers, RickerPeakAndTroughAreAtTheirClosedFormTimes) {
  const double fp = 1.0, t0 = 2.0037;
  Trace tr = sample_trace(800, 0.01, ricker, fp, t0);
  PickerOptions o;
  o.noise_end = 0.3;
  const Picks p = pick_travel_times(tr, o);
  EXPECT_NEAR(p.first_peak, t0, 1e-5);
  EXPECT_NEAR(p.peak_amplitude, 1.0, 1e-5);
  // The first trough is the side lobe before the peak, at t0 - sqrt(3/2)/(pi fp), depth
  // -2 exp(-3/2).
  // The trough is not symmetric: its third derivative leaves the parabolic vertex O(dt^2) off
  // (7e-3 dt here), far inside the half sample a picker without interpolation would miss.
  EXPECT_NEAR(p.first_trough, t0 - std::sqrt(1.5) / (M_PI * fp), 0.02 * 0.01);
  EXPECT_NEAR(p.trough_amplitude, -2 * std::exp(-1.5), 5e-5);
  EXPECT_LT(p.first_arrival, p.first_trough);
}

TEST(SignalPickers, NoiseFromThePreArrivalWindowSetsTheThreshold) {
  const double dt = 0.01, T = 2.0, t0 = 20.0, sigma = 0.02;
  Trace tr = sample_trace(3000, dt, raised_cosine, T, t0);
  for (double& a : tr.a) a += 0.3;  // a baseline offset the picker must remove
  add_noise(tr, sigma, 7);
  PickerOptions o;
  o.noise_end = 19.0, o.noise_factor = 5.0, o.relative_threshold = 0.0;
  const Picks p = pick_travel_times(tr, o);
  // 1900 noise samples: the RMS estimate has a relative standard error 1/sqrt(2 x 1900) = 1.6 %
  EXPECT_NEAR(p.noise_rms, sigma, 0.08 * sigma);
  EXPECT_NEAR(p.baseline, 0.3, 4 * sigma / std::sqrt(1900.0));
  EXPECT_DOUBLE_EQ(p.threshold, 5 * p.noise_rms);
  // The clean pulse crosses the threshold at tau_c; the noise (sigma) moves the crossing by
  // about sigma / slope there, a few samples at most.
  const double r = p.threshold;
  const double tau = T / (2 * M_PI) * std::acos(1 - 2 * r);
  const double slope = M_PI / T * std::sin(2 * M_PI * tau / T);
  EXPECT_NEAR(p.first_arrival, t0 + tau, 4 * sigma / slope);
  EXPECT_GT(p.first_arrival, 19.0);  // no pick inside the noise window
}

TEST(Spectrum, ParsevalHoldsForTheZeroPaddedEnergySpectrum) {
  Trace tr = ricker_source();
  add_noise(tr, 0.05, 3);
  for (int nfft : {4096, 4097, 8192, 10000}) {
    const Spectrum s = energy_spectrum(tr.a, tr.step(), nfft);
    EXPECT_NEAR(spectral_energy(s), s.time_energy, 1e-12 * s.time_energy) << "nfft " << nfft;
  }
}

TEST(Spectrum, DominantFrequencyOfARickerIsItsPeakFrequency) {
  for (double fp : {0.5, 1.0, 2.0}) {
    const Trace tr = sample_trace(4096, 0.01, ricker, fp, 10.0);
    const Spectrum s = energy_spectrum(tr.a, tr.step(), 1 << 16);
    // |A|^2 ~ f^4 exp(-2 f^2/fp^2) peaks at fp; the parabolic vertex over bins df apart is
    // exact to a small fraction of df.
    EXPECT_NEAR(s.dominant_frequency, fp, 0.05 * s.df) << "fp " << fp;
  }
}

TEST(Spectrum, MirroredWindowOfAHalfSineIsOneFullSinePeriod) {
  // A lobe sin(pi (t - t0)/D) on [t0, t0 + D]: up to its peak it is a quarter period of a
  // sine of period 2D, so the mirrored window is one period of that sine, with zero mean.
  const double dt = 0.001, D = 1.0, t0 = 1.0;
  Trace tr = sample_trace(
      4000, dt,
      [](double t, double d, double s) {
        return t > s && t < s + d ? std::sin(M_PI * (t - s) / d) : 0.0;
      },
      D, t0);
  PickerOptions o;
  o.noise_end = 0.5;
  const Picks p = pick_travel_times(tr, o);
  SpectrumOptions so;
  so.window = EventWindow::Mirrored;
  const Spectrum s = event_spectrum(tr, p, so);
  double mean = 0;
  for (double v : s.samples) mean += v;
  EXPECT_NEAR(mean, 0.0, 1e-9);
  EXPECT_NEAR((s.samples.size() - 1) * dt, 2 * D, 2.5 * dt);
  // One period P = 2D of a sine has |A(f)| ~ |sin(pi f P)/(1 - (f P)^2)|, whose maximum at
  // x = f P is found here on a fine grid (below the sine's own frequency, x = 0.84).
  double best = 0, xbest = 0;
  for (double x = 0.5; x < 1.0; x += 1e-6) {
    const double g = std::abs(std::sin(M_PI * x) / (1 - x * x));
    if (g > best) best = g, xbest = x;
  }
  EXPECT_NEAR(s.dominant_frequency, xbest / (2 * D), 0.1 * s.df);
}

// Whole traces: the ratio of the two spectra is exp(-pi f (t2 - t1)/Q) up to the truncation
// of the traces, 4e-5 of Q at Q = 5 (the slowest, widest pulse), 1e-6 at Q = 20.
TEST(SpectralRatio, RecoversTheQOfAConstantQWaveletExactly) {
  const Trace src = ricker_source();
  for (double q : {5.0, 20.0, 100.0}) {
    const double t1 = 5, t2 = 15;
    const Trace r1 = constant_q_propagate(src, t1, q, 1.0);
    const Trace r2 = constant_q_propagate(src, t2, q, 1.0);
    SpectrumOptions so;
    so.window = EventWindow::Whole;
    const Picks none;
    const Spectrum s1 = event_spectrum(r1, none, so), s2 = event_spectrum(r2, none, so);
    double f_lo, f_hi;
    common_band(s1, s2, 0.01, f_lo, f_hi);
    const SpectralRatioFit fit = spectral_ratio(s1, s2, t2 - t1, f_lo, f_hi);
    EXPECT_GT(fit.points, 100);
    EXPECT_NEAR(fit.q, q, 1e-4 * q) << "Q " << q;
    EXPECT_NEAR(fit.inv_q, 1 / q, 1e-4 / q);
    EXPECT_LT(fit.inv_q_error, 1e-4 / q);
  }
}

// Noise and windows: Gaussian noise of 1e-3 of the source peak, each event cut out by a span
// of 8 source periods around its picked peak. Over 20 noise seeds the estimates scatter
// about the true Q; the mean must lie within 3 standard errors of the mean of Q, and the
// spread must stay below 2 % (estimator_error in the signal_analysis scene charts it
// against the noise level and the band).
TEST(SpectralRatio, NoisyWindowedEventsGiveQWithinTheirScatter) {
  const Trace src = ricker_source();
  const double q = 20, t1 = 5, t2 = 15;
  const Trace c1 = constant_q_propagate(src, t1, q, 1.0);
  const Trace c2 = constant_q_propagate(src, t2, q, 1.0);
  std::vector<double> est;
  for (int seed = 1; seed <= 20; ++seed) {
    Trace r1 = c1, r2 = c2;
    add_noise(r1, 1e-3, 100 + seed);
    add_noise(r2, 1e-3, 200 + seed);
    PickerOptions po;
    po.noise_end = 3.0;
    const Picks p1 = pick_travel_times(r1, po), p2 = pick_travel_times(r2, po);
    SpectrumOptions so;
    so.window = EventWindow::Span;
    so.min_fft = 1 << 14;
    so.span_start = p1.first_peak - 4, so.span_end = p1.first_peak + 4;
    const Spectrum s1 = event_spectrum(r1, p1, so);
    so.span_start = p2.first_peak - 4, so.span_end = p2.first_peak + 4;
    const Spectrum s2 = event_spectrum(r2, p2, so);
    double f_lo, f_hi;
    common_band(s1, s2, 0.1, f_lo, f_hi);
    const SpectralRatioFit fit = spectral_ratio(s1, s2, t2 - t1, f_lo, f_hi);
    est.push_back(fit.q);
  }
  double mean = 0, var = 0;
  for (double v : est) mean += v / est.size();
  for (double v : est) var += (v - mean) * (v - mean) / (est.size() - 1);
  EXPECT_NEAR(mean, q, 3 * std::sqrt(var / est.size()) + 1e-3 * q);
  EXPECT_LT(std::sqrt(var), 0.02 * q);  // 0.15 (0.75 %) at these settings
}
