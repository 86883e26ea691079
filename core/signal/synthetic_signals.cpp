#include "core/signal/synthetic_signals.hpp"

#include <cmath>
#include <complex>

#include "core/run/rng.hpp"
#include "core/signal/real_fft.hpp"
#include "core/signal/spectrum.hpp"

namespace granular {

double ricker(double t, double fp, double t0) {
  const double u = std::pow(M_PI * fp * (t - t0), 2);
  return (1 - 2 * u) * std::exp(-u);
}

double raised_cosine(double t, double duration, double t0) {
  if (t <= t0 || t >= t0 + duration) return 0.0;
  return 0.5 * (1 - std::cos(2 * M_PI * (t - t0) / duration));
}

Trace sample_trace(int n, double dt, double (*shape)(double, double, double), double p1,
                   double p2) {
  Trace tr;
  tr.t.resize(n), tr.a.resize(n);
  for (int i = 0; i < n; ++i) tr.t[i] = i * dt, tr.a[i] = shape(i * dt, p1, p2);
  return tr;
}

Trace constant_q_propagate(const Trace& src, double T, double q, double f_ref) {
  src.validate("constant-Q source");
  const int n = src.size();
  RealFft fft(next_power_of_two(4 * n));
  const int nfft = fft.size(), nb = fft.bins();
  const double dt = src.step(), df = 1.0 / (nfft * dt);
  double* x = fft.in();
  fftw_complex* X = fft.out();
  for (int i = 0; i < nfft; ++i) x[i] = i < n ? src.a[i] : 0.0;
  fft.forward();
  for (int k = 0; k < nb; ++k) {
    const double f = k * df;
    double delay = T, decay = 0.0;
    if (std::isfinite(q) && k > 0) {
      decay = M_PI * f * T / q;
      delay = T * (1 - std::log(f / f_ref) / (M_PI * q));
    }
    const std::complex<double> h = std::exp(-decay) * std::polar(1.0, -2 * M_PI * f * delay);
    const std::complex<double> v = std::complex<double>(X[k][0], X[k][1]) * h;
    X[k][0] = v.real(), X[k][1] = v.imag();
  }
  if (nfft % 2 == 0) X[nb - 1][1] = 0.0;  // the Nyquist bin of a real signal is real
  fft.inverse();
  Trace out = src;
  for (int i = 0; i < n; ++i) out.a[i] = x[i] / nfft;
  return out;
}

void add_noise(Trace& tr, double sigma, std::uint64_t seed) {
  for (int i = 0; i < tr.size(); ++i) {
    Stream s(seed, static_cast<std::uint64_t>(i));
    tr.a[i] += sigma * s.normal();
  }
}

}  // namespace granular
