// Shared plumbing of the scenes that analyse signals (signal_analysis, wave_transmission):
// picker, spectrum and spectral-ratio settings from scene keys, and the JSON and HDF5
// records of a picked trace, its spectrum and a spectral-ratio fit.
//
//   [<prefix>.picker]    noise_end = 10.0   noise_factor = 5   relative_threshold = 0.02
//   [<prefix>.spectrum]  window = "lobe" | "mirrored" | "whole" | "span"   taper = 0
//                        pad_factor = 8   span = [t0, t1]   (window = "span": times relative
//                        to the trace's first peak)
//   [<prefix>.ratio]     band = [f_lo, f_hi]  (absent: the common band above band_fraction)
//                        band_fraction = 0.1   delay_picker = "first_peak"
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"
#include "core/signal/signal_pickers.hpp"
#include "core/signal/spectral_ratio.hpp"
#include "core/signal/spectrum.hpp"

namespace granular {

struct SignalSettings {
  PickerOptions picker;
  SpectrumOptions spectrum;
  double span[2] = {0, 0};   // relative to the first peak
  std::vector<double> band;  // empty: common band
  double band_fraction = 0.1;
  std::string delay_picker = "first_peak";
};

SignalSettings read_signal_settings(const SceneFile& scene, const std::string& prefix,
                                    double default_noise_end);

// first_arrival, first_peak or first_trough of the picks (NAN when not found).
double picked_time(const Picks& p, const std::string& which);

// The spectrum of the first event with the settings (span taken about the first peak),
// padded to at least min_fft.
Spectrum analyse_event(const Trace& tr, const Picks& p, const SignalSettings& s, int min_fft = 0);

// The spectral ratio of two events with the settings: same FFT length for both; the band
// from the settings or the common band; delay from the settings' picker.
SpectralRatioFit analyse_ratio(const Trace& t1, const Picks& p1, const Trace& t2, const Picks& p2,
                               const SignalSettings& s, double delay = -1);

Json picks_json(const Picks& p);
Json spectrum_json(const Spectrum& s);
Json ratio_json(const SpectralRatioFit& r);
// The units of a trace's time and amplitude (H5MD spelling, core/io/dataset_units.hpp). Its
// spectrum's frequencies are in time^-1, its energies |A(f)|^2 in (amplitude time)^2 (A(f) =
// dt sum a_n e^(-2 pi i f t_n)) and its windowed samples in the amplitude's unit.
struct TraceUnits {
  std::string time, amplitude;
};
std::string frequency_unit(const TraceUnits& u);
std::string energy_unit(const TraceUnits& u);

// The H5MD unit string of the product of units raised to powers, e.g. {{"mm us-1", 2},
// {"us", 2}} -> "mm+2": symbols in the order they first appear, powers summed, "1" when
// nothing is left; a leading numeric factor ("60 s") is raised too.
std::string unit_product(const std::vector<std::pair<std::string, int>>& factors);

// /<group>/{time, amplitude} of the trace, /<group>/spectrum/{frequency, energy, samples}
// (each with its unit from `units`) and the picks as attributes of <group>.
void write_signal(H5Writer& h5, const std::string& group, const Trace& tr, const Picks& p,
                  const Spectrum& s, const TraceUnits& units);

}  // namespace granular
