// Synthetic pulses with known properties, used to validate the pickers, the spectra and the
// spectral-ratio estimator, and as source pulses of the wave scene: Ricker wavelets,
// raised-cosine pulses, and a pulse propagated through a constant-Q medium.
#pragma once
#include <cstdint>
#include <vector>

#include "core/signal/trace.hpp"

namespace granular {

// Ricker wavelet of peak frequency fp centred at t0: (1 - 2 u) exp(-u), u = (pi fp (t - t0))^2.
// Its peak is at t0, its troughs at t0 -+ sqrt(3/2)/(pi fp), and its amplitude spectrum
// |A(f)| ~ f^2 exp(-f^2/fp^2) peaks at fp.
double ricker(double t, double fp, double t0);

// Raised cosine of duration T starting at t0: (1 - cos(2 pi (t - t0)/T))/2 inside, 0 outside;
// one-signed, smooth, peak 1 at t0 + T/2.
double raised_cosine(double t, double duration, double t0);

// A trace of n samples at interval dt starting at t = 0.
Trace sample_trace(int n, double dt, double (*shape)(double, double, double), double p1, double p2);

// The source trace after travel time T through a medium of constant Q (Kolsky-Futterman:
// |A(f)| multiplied by exp(-pi f T/Q), phase delay 2 pi f T (1 - ln(f/f_ref)/(pi Q)), the
// causal dispersion of a constant Q). Computed in the frequency domain on a grid padded to
// at least 4 x the trace length, so the result is periodic only beyond the returned samples.
// Q = inf: a pure delay.
Trace constant_q_propagate(const Trace& source, double travel_time, double q, double f_ref);

// Adds Gaussian white noise of standard deviation sigma from the stream (seed, sample index).
void add_noise(Trace& trace, double sigma, std::uint64_t seed);

}  // namespace granular
