// Energy per wavenumber: the FFT formula against the dense DFT matrix definition
// T^E = F TE F^-1 (brute force), and the trace identity sum_k TE^(k) = sum_p TE_p.
#include <gtest/gtest.h>

#include <complex>

#include "kernels/chain/chain_energy.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

namespace {
using Host = Kokkos::DefaultHostExecutionSpace;

ChainBatch<Host> evolved(ChainBoundary bc, int n, int realizations) {
  ChainSpec s;
  s.beads = n, s.boundary = bc, s.force = ChainForce::Hertz, s.xi = 0.3, s.seed = 5;
  ChainBatch<Host> c(s, ChainBatch<Host>::first(realizations));
  chain_set_impulse(c, 1, 0.01);
  chain_accelerations(c);
  chain_advance(c, 0.1, 137);
  return c;
}
}  // namespace

TEST(ChainSpectrum, FftDiagonalMatchesTheDenseFourierTransformOfTheEnergyMatrix) {
  for (auto bc : {ChainBoundary::Fixed, ChainBoundary::Periodic}) {
    const int n = bc == ChainBoundary::Fixed ? 15 : 16;
    auto c = evolved(bc, n, 2);
    ChainSpectrum spec(2, chain_lattice(c.spec));
    chain_spectrum(spec, c);
    const int L = c.spec.sites(), off = L - n;
    // Dense reference on the lattice sites: TE_pq = 1/2 b_p v_p v_q - 1/2 F_p u_q.
    std::vector<double> u(L, 0), v(L, 0), bv(L, 0), F(L, 0);
    auto hu = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.u);
    auto hv = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.v);
    auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.b);
    auto hk = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.klin);
    const int r = 1;
    for (int i = 0; i < n; ++i) {
      const double ul = i == 0 ? (off ? 0.0 : hu(r, n - 1)) : hu(r, i - 1);
      const double ur = i == n - 1 ? (off ? 0.0 : hu(r, 0)) : hu(r, i + 1);
      const int right = (i + 1) % c.C;
      u[i + off] = hu(r, i), v[i + off] = hv(r, i), bv[i + off] = hb(r, i) * hv(r, i);
      F[i + off] = hk(r, i) * (ul - hu(r, i)) - hk(r, right) * (hu(r, i) - ur);
    }
    using cd = std::complex<double>;
    std::vector<double> folded(L / 2 + 1, 0.0);
    double total = 0;
    for (int p = 0; p < L; ++p) total += 0.5 * bv[p] * v[p] - 0.5 * F[p] * u[p];
    for (int k = 0; k < L; ++k) {
      cd diag = 0;  // (F TE F^-1)_kk = sum_pq F_kp TE_pq Finv_qk
      for (int p = 0; p < L; ++p)
        for (int q = 0; q < L; ++q) {
          const double te = 0.5 * bv[p] * v[q] - 0.5 * F[p] * u[q];
          diag += std::polar(1.0, -2 * M_PI * k * p / L) * te *
                  std::polar(1.0 / L, 2 * M_PI * q * k / L);
        }
      folded[std::min(k, L - k)] += diag.real();
    }
    double sum = 0;
    for (int j = 0; j <= L / 2; ++j) {
      EXPECT_NEAR(spec.bins()[r * (L / 2 + 1) + j], folded[j], 1e-12 * std::abs(total))
          << "bin " << j;
      sum += spec.bins()[r * (L / 2 + 1) + j];
    }
    EXPECT_NEAR(sum / total, 1.0, 1e-12);
  }
}

TEST(ChainSpectrum, SpectralEnergiesSumToTheRealSpaceTotal) {
  auto c = evolved(ChainBoundary::Fixed, 255, 4);
  ChainSpectrum spec(4, chain_lattice(c.spec));
  chain_spectrum(spec, c);
  const auto totals = chain_totals(c);
  const int nb = 129;
  for (int r = 0; r < 4; ++r) {
    double sum = 0;
    for (int j = 0; j < nb; ++j) sum += spec.bins()[r * nb + j];
    EXPECT_NEAR(sum / totals.linear[r], 1.0, 1e-12);
  }
  // Disorder gives each |k| an imaginary part that cancels in the sum; it is reported.
  EXPECT_GT(spec.max_imag(), 0.0);
  const auto bands = chain_band_energies(spec.bins(), 4, 256, 32);
  double band_sum = 0;
  for (int b = 0; b < 32; ++b) band_sum += bands[b];
  EXPECT_NEAR(band_sum / totals.linear[0], 1.0, 1e-12);
}

TEST(ChainSpectrum, BandsOfWidthPiOverBCoverEveryWavenumberAndTonesSitInsideTheirBand) {
  EXPECT_EQ(chain_band_of_bin(0, 256, 32), 0);
  EXPECT_EQ(chain_band_of_bin(4, 256, 32), 0);
  EXPECT_EQ(chain_band_of_bin(5, 256, 32), 1);
  EXPECT_EQ(chain_band_of_bin(128, 256, 32), 31);
  for (int b = 0; b < 32; ++b)
    EXPECT_EQ(chain_band_of_bin(chain_band_tone(b, 256, 32), 256, 32), b);
}

TEST(ChainSpectrum, UpperEdgeTonesAreTheSourcesFourR) {
  // The source agitates N = 4, 8, ..., 128 for L = 256, B = 32: band r - 1 for N = 4r; the
  // last, N = 128 = L/2, is zero on every bead, so band 31 takes N = 127.
  for (int b = 0; b < 32; ++b) {
    EXPECT_EQ(chain_band_edge_tone(b, 256, 32), b < 31 ? 4 * (b + 1) : 127);
    EXPECT_EQ(chain_band_of_bin(chain_band_edge_tone(b, 256, 32), 256, 32), b);
    if (b + 1 < 32) {  // the next bin opens the next band
      EXPECT_EQ(chain_band_of_bin(chain_band_edge_tone(b, 256, 32) + 1, 256, 32), b + 1);
    }
  }
}

// A standing tone of the ordered chain puts all its energy into the tone's own bin.
TEST(ChainSpectrum, OrderedStandingToneIsASingleWavenumber) {
  ChainSpec s;
  s.beads = 63, s.xi = 0.0, s.force = ChainForce::Linear;
  ChainBatch<Host> c(s, {0});
  chain_set_standing_waves(c, {9}, 1, 1e-3);
  chain_accelerations(c);
  chain_advance(c, 0.05, 333);
  ChainSpectrum spec(1, chain_lattice(s));
  chain_spectrum(spec, c);
  const double total = chain_totals(c).linear[0];
  EXPECT_NEAR(spec.bins()[9] / total, 1.0, 1e-12);
}
