// A real-to-complex FFT of one length with its FFTW buffers and plans behind RAII: forward
// (in -> out) and, for filtering in the frequency domain, inverse (out -> in, unnormalised).
#pragma once
#include <fftw3.h>

#include <string>

#include "core/run/error.hpp"

namespace granular {

class RealFft {
 public:
  explicit RealFft(int nfft) : n_(nfft) {
    in_ = fftw_alloc_real(n_);
    out_ = fftw_alloc_complex(n_ / 2 + 1);
    if (!in_ || !out_) throw PhysicsError("FFT: out of memory for length " + std::to_string(n_));
    // FFTW_ESTIMATE: the same plan, and so the same rounding, on every run.
    forward_ = fftw_plan_dft_r2c_1d(n_, in_, out_, FFTW_ESTIMATE);
    inverse_ = fftw_plan_dft_c2r_1d(n_, out_, in_, FFTW_ESTIMATE);
    if (!forward_ || !inverse_)
      throw PhysicsError("FFT: FFTW could not plan length " + std::to_string(n_));
  }
  ~RealFft() {
    if (forward_) fftw_destroy_plan(forward_);
    if (inverse_) fftw_destroy_plan(inverse_);
    fftw_free(in_);
    fftw_free(out_);
  }
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  int size() const { return n_; }
  int bins() const { return n_ / 2 + 1; }
  double* in() { return in_; }
  fftw_complex* out() { return out_; }
  void forward() { fftw_execute(forward_); }
  void inverse() { fftw_execute(inverse_); }  // overwrites out()

 private:
  int n_;
  double* in_ = nullptr;
  fftw_complex* out_ = nullptr;
  fftw_plan forward_ = nullptr, inverse_ = nullptr;
};

}  // namespace granular
