// Energies of batched chains (docs/model_chains.md §4): per-bead kinetic + linearized potential
// energy, per-realization totals (linearized and exact Hertz), centre of energy R and
// mean squared width r^2, ensemble averages, and the divergence guard. Every reduction
// runs in a fixed order, so results do not depend on the thread count.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "core/chain/chain_spectrum.hpp"
#include "kernels/chain/chain_batch.hpp"
#include "kernels/chain/chain_verlet.hpp"

namespace granular {

struct ChainTotals {
  std::vector<double> kinetic;  // sum 1/2 b v^2
  std::vector<double> linear;   // kinetic + 1/2 sum k_c (u_l - u_r)^2 (= -1/2 u.K u)
  std::vector<double> hertz;    // kinetic + exact Hertz potential relative to rest
  std::vector<double> centre;   // R = sum p TE_p / sum TE_p (p = bead index)
  std::vector<double> width2;   // r^2 = sum (p - R)^2 TE_p / sum TE_p
  double max_abs(const std::vector<double>& x) const {
    double m = 0;
    for (double y : x) m = std::max(m, std::abs(y));
    return m;
  }
};

// Per-bead total energy TE_p = 1/2 b_p v_p^2 - 1/2 F_p u_p with linearized forces F = K u.
template <class Space>
void chain_bead_energies(
    const ChainBatch<Space>& c,
    const Kokkos::View<double**, Kokkos::LayoutRight, typename Space::memory_space>& te) {
  const int N = c.N, C = c.C;
  const bool periodic = c.spec.boundary == ChainBoundary::Periodic;
  auto u = c.u, v = c.v, b = c.b, klin = c.klin;
  Kokkos::parallel_for(
      "chain::bead_energies", Kokkos::MDRangePolicy<Space, Kokkos::Rank<2>>({0, 0}, {c.R, N}),
      KOKKOS_LAMBDA(const int r, const int i) {
        const double ul = i == 0 ? (periodic ? u(r, N - 1) : 0.0) : u(r, i - 1);
        const double ur = i == N - 1 ? (periodic ? u(r, 0) : 0.0) : u(r, i + 1);
        const int right = i + 1 == C ? 0 : i + 1;
        const double F = klin(r, i) * (ul - u(r, i)) - klin(r, right) * (u(r, i) - ur);
        te(r, i) = 0.5 * b(r, i) * v(r, i) * v(r, i) - 0.5 * F * u(r, i);
      });
}

template <class Space>
ChainTotals chain_totals(const ChainBatch<Space>& c) {
  using mem = typename Space::memory_space;
  const int N = c.N, C = c.C;
  const bool periodic = c.spec.boundary == ChainBoundary::Periodic;
  Kokkos::View<double**, Kokkos::LayoutRight, mem> te("chain::te", c.R, N);
  chain_bead_energies(c, te);
  Kokkos::View<double**, Kokkos::LayoutRight, mem> out("chain::totals", c.R, 5);
  auto u = c.u, v = c.v, b = c.b, kappa = c.kappa, delta0 = c.delta0, klin = c.klin;
  Kokkos::parallel_for(
      "chain::totals", Kokkos::RangePolicy<Space>(0, c.R), KOKKOS_LAMBDA(const int r) {
        double ke = 0, pe_lin = 0, pe_hertz = 0;
        for (int i = 0; i < N; ++i) ke += 0.5 * b(r, i) * v(r, i) * v(r, i);
        for (int k = 0; k < C; ++k) {
          const double ul = k == 0 ? (periodic ? u(r, N - 1) : 0.0) : u(r, k - 1);
          const double ur = k == N ? 0.0 : u(r, k);
          const double du = ul - ur;
          pe_lin += 0.5 * klin(r, k) * du * du;
          // Hertz potential (2/5) kappa delta^{5/2} minus its value and its (unit) force
          // at rest, so the energy of the resting chain is zero.
          const double d = delta0(r, k) + du, d0 = delta0(r, k);
          const double d_pos = d > 0 ? d : 0.0;
          pe_hertz += 0.4 * kappa(r, k) *
                          (d_pos * d_pos * Kokkos::Experimental::sqrt(d_pos) -
                           d0 * d0 * Kokkos::Experimental::sqrt(d0)) -
                      du;
        }
        double e = 0, m1 = 0;
        for (int i = 0; i < N; ++i) e += te(r, i), m1 += i * te(r, i);
        const double centre = m1 / e;
        double m2 = 0;
        for (int i = 0; i < N; ++i) m2 += (i - centre) * (i - centre) * te(r, i);
        out(r, 0) = ke;
        out(r, 1) = ke + pe_lin;
        out(r, 2) = ke + pe_hertz;
        out(r, 3) = centre;
        out(r, 4) = m2 / e;
      });
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), out);
  ChainTotals t;
  for (int r = 0; r < c.R; ++r) {
    t.kinetic.push_back(h(r, 0));
    t.linear.push_back(h(r, 1));
    t.hertz.push_back(h(r, 2));
    t.centre.push_back(h(r, 3));
    t.width2.push_back(h(r, 4));
  }
  return t;
}

// Ensemble mean over realizations of a (R x N) field, bead by bead in realization order.
template <class Space>
std::vector<double> chain_ensemble_mean(
    const Kokkos::View<double**, Kokkos::LayoutRight, typename Space::memory_space>& field) {
  const int R = field.extent(0), N = field.extent(1);
  Kokkos::View<double*, typename Space::memory_space> mean("chain::mean", N);
  Kokkos::parallel_for(
      "chain::ensemble_mean", Kokkos::RangePolicy<Space>(0, N), KOKKOS_LAMBDA(const int i) {
        double s = 0;
        for (int r = 0; r < R; ++r) s += field(r, i);
        mean(i) = s / R;
      });
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mean);
  return std::vector<double>(h.data(), h.data() + N);
}

// One bead's column of a (R x N) field, realization by realization, on the host.
template <class Space>
std::vector<double> chain_bead_column(
    const Kokkos::View<double**, Kokkos::LayoutRight, typename Space::memory_space>& field,
    int bead) {
  const int R = field.extent(0);
  Kokkos::View<double*, typename Space::memory_space> column("chain::column", R);
  Kokkos::parallel_for(
      "chain::bead_column", Kokkos::RangePolicy<Space>(0, R),
      KOKKOS_LAMBDA(const int r) { column(r) = field(r, bead); });
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), column);
  return std::vector<double>(h.data(), h.data() + R);
}

// Stability of the time step: an estimate of the highest mode frequency from Gershgorin's
// bound on M^{-1}(-K) (exact, 2 sqrt(3/2), for the ordered chain).
template <class Space>
double chain_omega_max_bound(const ChainBatch<Space>& c) {
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.b);
  auto hk = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.klin);
  double w2 = 0;
  for (int r = 0; r < c.R; ++r)
    for (int i = 0; i < c.N; ++i) {
      const int right = i + 1 == c.C ? 0 : i + 1;
      w2 = std::max(w2, 2.0 * (hk(r, i) + hk(r, right)) / hb(r, i));
    }
  return std::sqrt(w2);
}

// Verlet stability limit 2/omega_max of each realization. Fixed walls: omega_max^2 is the
// largest eigenvalue of the symmetric tridiagonal M^{-1/2}(-K)M^{-1/2}, found by bisection
// on its Sturm sequence (exact to round-off, O(N) per iteration). A ring's closing contact
// breaks the tridiagonal form; there Gershgorin's bound is used (a safe underestimate).
template <class Space>
std::vector<double> chain_stability_limits(const ChainBatch<Space>& c) {
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.b);
  auto hk = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.klin);
  std::vector<double> limits(c.R);
  const int N = c.N;
  for (int r = 0; r < c.R; ++r) {
    double gersh = 0;
    for (int i = 0; i < N; ++i) {
      const int right = i + 1 == c.C ? 0 : i + 1;
      gersh = std::max(gersh, 2.0 * (hk(r, i) + hk(r, right)) / hb(r, i));
    }
    double w2 = gersh;
    if (c.spec.boundary == ChainBoundary::Fixed) {
      auto count_below = [&](double x) {  // eigenvalues < x
        int neg = 0;
        double q = 1.0;
        for (int i = 0; i < N; ++i) {
          const double d = (hk(r, i) + hk(r, i + 1)) / hb(r, i);
          const double e2 = i == 0 ? 0.0 : hk(r, i) * hk(r, i) / (hb(r, i - 1) * hb(r, i));
          q = d - x - (i == 0 ? 0.0 : e2 / q);
          if (q == 0.0) q = -1e-300;
          if (q < 0) ++neg;
        }
        return neg;
      };
      double lo = 0.0, hi = gersh * (1 + 1e-12);
      for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (count_below(mid) < N ? lo : hi) = mid;
      }
      w2 = hi;
    }
    limits[r] = 2.0 / std::sqrt(w2);
  }
  return limits;
}

// Refuses a time step at or beyond the stability limit of any realization, naming it and
// its lightest bead, before any step is taken.
template <class Space>
void chain_check_time_step(const ChainBatch<Space>& c, double dt) {
  const auto limits = chain_stability_limits(c);
  const int worst =
      static_cast<int>(std::min_element(limits.begin(), limits.end()) - limits.begin());
  if (dt < limits[worst]) return;
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.b);
  double lightest = hb(worst, 0);
  for (int i = 0; i < c.N; ++i) lightest = std::min(lightest, hb(worst, i));
  std::ostringstream msg;
  msg << "time step dt = " << dt
      << " is beyond the Verlet stability limit 2/omega_max = " << limits[worst]
      << " of chain realization " << c.realization[worst] << " (xi = " << c.spec.xi
      << ", lightest bead b = " << lightest << "): light beads vibrate fast. Use dt below "
      << limits[worst]
      << ", or keep near-weightless beads out with a mass floor (disorder.min_mass).";
  throw PhysicsError(msg.str());
}

// Divergence guard: stops the run when any realization's conserved energy is NaN or has
// grown by more than `growth` over its initial value. Bounded Verlet runs near the edge of
// stability show energy oscillations of up to ~1/(1 - (w dt/2)^2); an unstable step
// grows exponentially, so a large factor separates the two cleanly.
template <class Space>
void chain_check_energy(const ChainBatch<Space>& c, const std::vector<double>& initial,
                        const std::vector<double>& now, double dt, double growth) {
  for (int r = 0; r < c.R; ++r) {
    if (std::isfinite(now[r]) && std::abs(now[r]) <= growth * std::abs(initial[r])) continue;
    std::ostringstream msg;
    msg << "chain realization " << c.realization[r] << " diverged at t = " << c.time << ": energy "
        << now[r] << " against " << initial[r] << " at the start. The time step dt = " << dt
        << " is beyond the Verlet stability limit 2/omega_max (about "
        << 2.0 / chain_omega_max_bound(c) << " for this batch); reduce dt.";
    throw PhysicsError(msg.str());
  }
}

// Verlet steps in chunks with the divergence guard after each chunk; returns the totals
// at the end. `initial` holds the conserved energies at the start of the run.
template <class Space>
ChainTotals chain_advance_guarded(ChainBatch<Space>& c, double dt, long steps,
                                  const std::vector<double>& initial, double growth = 1e4,
                                  long chunk = 64) {
  ChainTotals t;
  for (long done = 0; done < steps;) {
    const long n = std::min(chunk, steps - done);
    chain_advance(c, dt, n);
    done += n;
    t = chain_totals(c);
    chain_check_energy(c, initial, c.spec.force == ChainForce::Hertz ? t.hertz : t.linear, dt,
                       growth);
  }
  return t;
}

inline ChainLattice chain_lattice(const ChainSpec& s) {
  ChainLattice l;
  l.beads = s.beads, l.contacts = s.contacts(), l.sites = s.sites();
  l.periodic = s.boundary == ChainBoundary::Periodic;
  return l;
}

// Energy per wavenumber of every realization of the batch (host FFTs).
template <class Space>
void chain_spectrum(ChainSpectrum& spectrum, const ChainBatch<Space>& c) {
  auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.u);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.v);
  auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.b);
  auto k = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.klin);
  spectrum.compute(u.data(), v.data(), b.data(), k.data());
}

}  // namespace granular
