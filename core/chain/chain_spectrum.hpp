// Energy per wavenumber of batched chains (docs/model_chains.md §4) without any dense DFT
// matrix: the total-energy matrix TE_pq = 1/2 b_p v_p v_q - 1/2 F_p u_q is a sum of two
// outer products, so the diagonal of F TE F^-1 is
//   TE^(k) = (1/2L) [ DFT(b v)_k conj(DFT(v)_k) - DFT(F)_k conj(DFT(u)_k) ]
// for real lattice vectors of length L. Four real-to-complex FFTs per realization (one
// batched FFTW plan for the whole ensemble), O(L log L) each.
#pragma once
#include <fftw3.h>

#include <vector>

namespace granular {

struct ChainLattice {
  int beads = 0;     // N
  int contacts = 0;  // C
  int sites = 0;     // L, the transform length (N + 1 with the wall site 0, or N)
  bool periodic = false;
  int bins() const { return sites / 2 + 1; }  // |k| = 2 pi j / L, j = 0 .. L/2
};

class ChainSpectrum {
 public:
  ChainSpectrum(int realizations, const ChainLattice& lattice);
  ~ChainSpectrum();
  ChainSpectrum(const ChainSpectrum&) = delete;
  ChainSpectrum& operator=(const ChainSpectrum&) = delete;

  // Row-major host arrays: u, v, b are R x N, klin is R x C. Fills bins() (R x bins:
  // energy per |k|, the k and -k entries folded together) and max_imag().
  void compute(const double* u, const double* v, const double* b, const double* klin);

  const std::vector<double>& bins() const { return bins_; }
  // Largest |Im TE^(k)| relative to the realization's total energy (a diagnostic: the
  // imaginary parts of a disordered chain cancel in the sum over k).
  double max_imag() const { return max_imag_; }
  const ChainLattice& lattice() const { return lat_; }

 private:
  int R_;
  ChainLattice lat_;
  double* in_ = nullptr;         // R x 4 x L
  fftw_complex* out_ = nullptr;  // R x 4 x bins
  fftw_plan plan_ = nullptr;
  std::vector<double> bins_;
  double max_imag_ = 0;
};

// Band r of B collects the bins j with (j - 1) * B / (L/2) == r (bin 0 joins band 0), so
// B bands of width pi/B cover 0 < k <= pi.
int chain_band_of_bin(int bin, int sites, int bands);
// R x bins -> R x B band energies.
std::vector<double> chain_band_energies(const std::vector<double>& bins, int realizations,
                                        int sites, int bands);
// The standing-wave tone placed at the centre of band r.
int chain_band_tone(int band, int sites, int bands);
// The tone at the upper edge of band r (its last bin): the source's N = 4 (r + 1) for
// L = 256 sites and 32 bands, except for the last band, whose edge N = L/2 vanishes on
// every bead (sin(pi i)): it gets the bin below, N = L/2 - 1.
int chain_band_edge_tone(int band, int sites, int bands);

}  // namespace granular
