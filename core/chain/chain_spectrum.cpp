#include "core/chain/chain_spectrum.hpp"

#include <cmath>
#include <string>

#include "core/run/error.hpp"

namespace granular {

ChainSpectrum::ChainSpectrum(int realizations, const ChainLattice& lattice)
    : R_(realizations), lat_(lattice) {
  const int L = lat_.sites, nb = lat_.bins();
  in_ = fftw_alloc_real(static_cast<size_t>(R_) * 4 * L);
  out_ = fftw_alloc_complex(static_cast<size_t>(R_) * 4 * nb);
  if (!in_ || !out_) throw PhysicsError("chain spectrum: out of memory for the FFT buffers");
  int n[1] = {L};
  // FFTW_ESTIMATE: the plan (and so every rounding) is the same on every run.
  plan_ =
      fftw_plan_many_dft_r2c(1, n, 4 * R_, in_, nullptr, 1, L, out_, nullptr, 1, nb, FFTW_ESTIMATE);
  if (!plan_) throw PhysicsError("chain spectrum: FFTW could not plan length " + std::to_string(L));
  bins_.assign(static_cast<size_t>(R_) * nb, 0.0);
}

ChainSpectrum::~ChainSpectrum() {
  if (plan_) fftw_destroy_plan(plan_);
  fftw_free(in_);
  fftw_free(out_);
}

void ChainSpectrum::compute(const double* u, const double* v, const double* b, const double* klin) {
  const int N = lat_.beads, C = lat_.contacts, L = lat_.sites, nb = lat_.bins();
  const int off = lat_.periodic ? 0 : 1;  // site of bead 0
  for (int r = 0; r < R_; ++r) {
    const double* ur = u + static_cast<size_t>(r) * N;
    const double* vr = v + static_cast<size_t>(r) * N;
    const double* br = b + static_cast<size_t>(r) * N;
    const double* kr = klin + static_cast<size_t>(r) * C;
    double* bv = in_ + static_cast<size_t>(r) * 4 * L;
    double* vv = bv + L;
    double* ff = vv + L;
    double* uu = ff + L;
    for (int x = 0; x < L; ++x) bv[x] = vv[x] = ff[x] = uu[x] = 0.0;  // wall site stays 0
    for (int i = 0; i < N; ++i) {
      const double ul = i == 0 ? (lat_.periodic ? ur[N - 1] : 0.0) : ur[i - 1];
      const double uright = i == N - 1 ? (lat_.periodic ? ur[0] : 0.0) : ur[i + 1];
      const int right = i + 1 == C ? 0 : i + 1;
      bv[i + off] = br[i] * vr[i];
      vv[i + off] = vr[i];
      ff[i + off] = kr[i] * (ul - ur[i]) - kr[right] * (ur[i] - uright);
      uu[i + off] = ur[i];
    }
  }
  fftw_execute(plan_);
  max_imag_ = 0;
  for (int r = 0; r < R_; ++r) {
    const fftw_complex* BV = out_ + static_cast<size_t>(r) * 4 * nb;
    const fftw_complex* V = BV + nb;
    const fftw_complex* F = V + nb;
    const fftw_complex* U = F + nb;
    double* e = bins_.data() + static_cast<size_t>(r) * nb;
    double total = 0, imag = 0;
    for (int j = 0; j < nb; ++j) {
      // a conj(b) = (ar br + ai bi) + i (ai br - ar bi)
      const double re =
          (BV[j][0] * V[j][0] + BV[j][1] * V[j][1]) - (F[j][0] * U[j][0] + F[j][1] * U[j][1]);
      const double im =
          (BV[j][1] * V[j][0] - BV[j][0] * V[j][1]) - (F[j][1] * U[j][0] - F[j][0] * U[j][1]);
      // k and -k carry complex-conjugate entries: fold them (bins 0 and L/2 are their own
      // partners).
      const bool self = j == 0 || 2 * j == L;
      e[j] = (self ? 1.0 : 2.0) * re / (2.0 * L);
      total += e[j];
      imag = std::max(imag, std::abs(im) / (2.0 * L));
    }
    if (total != 0) max_imag_ = std::max(max_imag_, imag / std::abs(total));
  }
}

int chain_band_of_bin(int bin, int sites, int bands) {
  const int half = sites / 2;
  if (bin <= 0) return 0;
  return static_cast<int>((static_cast<long>(bin - 1) * bands) / half);
}

std::vector<double> chain_band_energies(const std::vector<double>& bins, int realizations,
                                        int sites, int bands) {
  const int nb = sites / 2 + 1;
  if (bands < 1 || bands > sites / 2)
    throw InputError("band count " + std::to_string(bands) +
                     " must be between 1 and L/2 = " + std::to_string(sites / 2));
  std::vector<double> e(static_cast<size_t>(realizations) * bands, 0.0);
  for (int r = 0; r < realizations; ++r)
    for (int j = 0; j < nb; ++j)
      e[static_cast<size_t>(r) * bands + chain_band_of_bin(j, sites, bands)] +=
          bins[static_cast<size_t>(r) * nb + j];
  return e;
}

int chain_band_tone(int band, int sites, int bands) {
  // Bins of band r: the j with floor((j - 1) B / (L/2)) = r; pick the middle one.
  int lo = -1, hi = -1;
  for (int j = 1; j <= sites / 2; ++j)
    if (chain_band_of_bin(j, sites, bands) == band) {
      if (lo < 0) lo = j;
      hi = j;
    }
  if (lo < 0) throw InputError("band " + std::to_string(band) + " holds no wavenumber");
  return (lo + hi) / 2;
}

int chain_band_edge_tone(int band, int sites, int bands) {
  int last = -1;
  for (int j = 1; j <= sites / 2; ++j)
    if (chain_band_of_bin(j, sites, bands) == band) last = j;
  // N = L/2 is sin(pi i) = 0 at every bead: the last band takes the bin below it.
  return last == sites / 2 ? last - 1 : last;
}

}  // namespace granular
