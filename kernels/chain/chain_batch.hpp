// Batched disordered granular chains (docs/model_chains.md): the state of R realizations of an
// N-bead chain as Kokkos Views indexed (realization, bead), plus the per-realization
// disorder drawn from a reproducible stream (seed, realization index).
//
// Contacts are numbered so that contact c joins bead c-1 (left) and bead c (right).
// Fixed walls: C = N + 1 contacts, contact 0 joins the left wall and bead 0, contact N
// joins bead N-1 and the right wall. Periodic: C = N contacts, contact 0 joins bead N-1
// and bead 0. So bead i always feels contact i on its left and contact (i+1) mod C on
// its right.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/run/error.hpp"
#include "core/run/rng.hpp"

namespace granular {

enum class ChainBoundary { Fixed, Periodic };
enum class ChainForce { Hertz, Linear };
// Pair stiffness from the masses: radius rule sqrt(2/(b_i^{1/3}+b_j^{1/3})) (b_i b_j)^{1/6}
// (same material, radius ~ b^{1/3}; the default) or mass rule sqrt(2/(b_i+b_j)) (b_i b_j)^{1/6}.
enum class StiffnessRule { Radius, Mass };
// Disorder on mass and (through kappa and Delta) on contact stiffness, or on mass only.
enum class DisorderTarget { MassAndStiffness, MassOnly };
// Which Verlet kernel advances the batch (kernels/chain/chain_verlet.hpp): the sweep over
// the global arrays, the on-chip one that holds a realization in its team's registers for
// all the steps of one call (kernels/chain/chain_on_chip.hpp), or the on-chip one on a
// device where a chain fits a team and the global sweep elsewhere. Both give the same bits.
enum class ChainKernel { Auto, Global, OnChip };

ChainBoundary parse_chain_boundary(const std::string& s);
ChainForce parse_chain_force(const std::string& s);
StiffnessRule parse_stiffness_rule(const std::string& s);
DisorderTarget parse_disorder_target(const std::string& s);
ChainKernel parse_chain_kernel(const std::string& s);

struct ChainSpec {
  int beads = 0;
  ChainBoundary boundary = ChainBoundary::Fixed;
  ChainForce force = ChainForce::Hertz;
  StiffnessRule rule = StiffnessRule::Radius;
  DisorderTarget target = DisorderTarget::MassAndStiffness;
  double xi = 0.0;  // standard deviation of the mass distribution (mean 1)
  // Draws at or below this are rejected (0: only non-positive masses, as in
  // docs/model_chains.md §2). A floor keeps near-weightless beads, whose frequency sqrt(k/b)
  // diverges, out of the chain.
  double min_mass = 0.0;
  std::uint64_t seed = 1;

  int contacts() const { return boundary == ChainBoundary::Fixed ? beads + 1 : beads; }
  // Length of the lattice vectors that are Fourier transformed: the left wall is site 0
  // for fixed walls (N + 1 = 2^M sites), the N beads themselves for a periodic ring.
  int sites() const { return boundary == ChainBoundary::Fixed ? beads + 1 : beads; }
  // Lattice site of bead i (site 0 is the wall for fixed boundaries).
  int site(int bead) const { return boundary == ChainBoundary::Fixed ? bead + 1 : bead; }
};

// Masses of one realization: normal(1, xi), draws <= min_mass rejected, rescaled so the
// sample mean is exactly 1. A pure function of (seed, realization index).
std::vector<double> chain_masses(const ChainSpec& spec, std::uint64_t realization);

double chain_pair_kappa(StiffnessRule rule, double bi, double bj);

template <class Space>
struct ChainBatch {
  using mem = typename Space::memory_space;
  using Field = Kokkos::View<double**, Kokkos::LayoutRight, mem>;  // beads contiguous
  ChainSpec spec;
  int R = 0, N = 0, C = 0;
  Field u, v, a;                   // displacement (units of Delta_0), velocity, acceleration
  Field b;                         // mass (units of m_0)
  Field kappa;                     // Hertz pair stiffness, per contact
  Field delta0;                    // static overlap kappa^{-2/3}: every contact carries F_0 = 1
  Field klin;                      // linearized stiffness (3/2) kappa^{2/3}
  Field force;                     // contact forces of the current step (scratch of the stepper)
  Kokkos::View<int*, mem> opened;  // 1 where a contact of the realization opened
  std::vector<std::uint64_t> realization;  // global index of each row (its disorder stream)
  double time = 0.0;
  ChainKernel kernel = ChainKernel::Auto;

  ChainBatch(const ChainSpec& s, const std::vector<std::uint64_t>& realizations)
      : spec(s),
        R(static_cast<int>(realizations.size())),
        N(s.beads),
        C(s.contacts()),
        u("chain::u", R, N),
        v("chain::v", R, N),
        a("chain::a", R, N),
        b("chain::b", R, N),
        kappa("chain::kappa", R, C),
        delta0("chain::delta0", R, C),
        klin("chain::klin", R, C),
        force("chain::force", R, C),
        opened("chain::opened", R),
        realization(realizations) {
    if (N < 2) throw InputError("a chain needs at least 2 beads (got " + std::to_string(N) + ")");
    auto hb = Kokkos::create_mirror_view(b);
    auto hk = Kokkos::create_mirror_view(kappa);
    auto hd = Kokkos::create_mirror_view(delta0);
    auto hl = Kokkos::create_mirror_view(klin);
    for (int r = 0; r < R; ++r) {
      const auto m = chain_masses(spec, realizations[r]);
      for (int i = 0; i < N; ++i) hb(r, i) = m[i];
      for (int c = 0; c < C; ++c) {
        // The wall "particles" of a fixed chain are immobile beads of unit mass.
        const double bl =
            c == 0 ? (spec.boundary == ChainBoundary::Fixed ? 1.0 : m[N - 1]) : m[c - 1];
        const double br = c == N ? 1.0 : m[c];
        const double k =
            spec.target == DisorderTarget::MassOnly ? 1.0 : chain_pair_kappa(spec.rule, bl, br);
        hk(r, c) = k;
        hd(r, c) = std::pow(k, -2.0 / 3.0);
        hl(r, c) = 1.5 * std::cbrt(k * k);
      }
    }
    Kokkos::deep_copy(b, hb);
    Kokkos::deep_copy(kappa, hk);
    Kokkos::deep_copy(delta0, hd);
    Kokkos::deep_copy(klin, hl);
  }

  // Realizations 0 .. R-1.
  static std::vector<std::uint64_t> first(int count) {
    std::vector<std::uint64_t> ids(count);
    for (int r = 0; r < count; ++r) ids[r] = static_cast<std::uint64_t>(r);
    return ids;
  }
};

// ---- initial conditions (docs/model_chains.md §3) -----------------------------------
template <class Space>
void chain_set_rest(ChainBatch<Space>& c) {
  Kokkos::deep_copy(c.u, 0.0);
  Kokkos::deep_copy(c.v, 0.0);
  Kokkos::deep_copy(c.a, 0.0);
  c.time = 0.0;
}

// v_bead = v0, everything else at rest.
template <class Space>
void chain_set_impulse(ChainBatch<Space>& c, int bead, double v0) {
  if (bead < 0 || bead >= c.N)
    throw InputError("impulse bead " + std::to_string(bead) + " is outside the chain (0.." +
                     std::to_string(c.N - 1) + ")");
  chain_set_rest(c);
  auto v = c.v;
  Kokkos::parallel_for(
      "chain::impulse", Kokkos::RangePolicy<Space>(0, c.R),
      KOKKOS_LAMBDA(const int r) { v(r, bead) = v0; });
}

// Superposed standing waves u = sum_t u0 sin(tone_t 2 pi x / L) at lattice site x of each
// bead (L = sites()), v = 0.
template <class Space>
void chain_set_standing_waves(ChainBatch<Space>& c, const std::vector<int>& tones_per_row,
                              int tones_each, double u0) {
  chain_set_rest(c);
  auto hu = Kokkos::create_mirror_view(c.u);
  const double L = c.spec.sites();
  for (int r = 0; r < c.R; ++r)
    for (int i = 0; i < c.N; ++i) {
      double s = 0.0;
      for (int t = 0; t < tones_each; ++t)
        s += u0 * std::sin(tones_per_row[r * tones_each + t] * 2.0 * M_PI * c.spec.site(i) / L);
      hu(r, i) = s;
    }
  Kokkos::deep_copy(c.u, hu);
}

}  // namespace granular
