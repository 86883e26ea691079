// Energy spectrum |A(f)|^2 of the first event of a received signal (FFTW, real to complex).
// A(f) = dt sum_n a_n exp(-2 pi i f t_n) approximates the continuous Fourier transform, so
// that sum over the full spectrum of |A|^2 df equals sum a_n^2 dt (Parseval, exactly).
#pragma once
#include <string>
#include <vector>

#include "core/signal/signal_pickers.hpp"
#include "core/signal/trace.hpp"

namespace granular {

enum class EventWindow {
  Whole,     // the whole trace
  Span,      // [span_start, span_end]
  Lobe,      // the first lobe: from the zero crossing before the first arrival to the next one
  Mirrored,  // onset up to the first extremum (a quarter period), mirrored to a half period
             // and repeated with the opposite sign: one full period of zero mean
};

EventWindow parse_event_window(const std::string& name, const std::string& key);
const char* event_window_name(EventWindow w);

struct SpectrumOptions {
  EventWindow window = EventWindow::Lobe;
  double span_start = 0, span_end = 0;  // Span only
  double taper = 0.0;                   // Tukey fraction (0: rectangular, 1: Hann)
  int pad_factor = 8;                   // zero padding: nfft >= pad_factor x window length
  int min_fft = 0;                      // nfft at least this (equal grids for spectral ratios)
};

struct Spectrum {
  double df = 0, dt = 0;
  int nfft = 0;
  std::vector<double> f, amplitude, energy;  // one-sided, f_k = k df, k = 0 .. nfft/2
  std::vector<double> samples;               // the windowed event that was transformed
  double window_start = 0, window_end = 0;   // times of the event's first and last sample
  double time_energy = 0;                    // sum samples^2 dt
  double dominant_frequency = 0;             // 0: the spectrum falls from f = 0 on
  double dominant_energy = 0;
};

// The spectrum of samples at interval dt, zero-padded to nfft (>= samples.size()).
Spectrum energy_spectrum(const std::vector<double>& samples, double dt, int nfft);

// The windowed first event of `trace` (baseline of `picks` removed) and its spectrum.
Spectrum event_spectrum(const Trace& trace, const Picks& picks, const SpectrumOptions& options);

// sum |A|^2 df over the full (two-sided) spectrum, from the one-sided half.
double spectral_energy(const Spectrum& s);

// Largest |A|^2 at f > 0 when it is a local maximum (vertex of the parabola through the
// three bins around it); 0 when the spectrum falls monotonically from f = 0.
double dominant_frequency(const Spectrum& s, double* energy = nullptr);

int next_power_of_two(int n);

}  // namespace granular
