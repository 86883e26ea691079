// Velocity Verlet for every realization of a chain batch in one parallel sweep: one team
// per realization advances its chain through many steps inside a single kernel, so the
// chain stays in cache (host) or in the team's L1 (GPU) between steps. The leapfrog form
// (one force pass and one kick-drift pass per step) computes each contact force once.
#pragma once
#include <Kokkos_Core.hpp>
#include <sstream>

#include "kernels/chain/chain_batch.hpp"
#include "kernels/chain/chain_contact_force.hpp"
#include "kernels/chain/chain_on_chip.hpp"

namespace granular {

template <class Space>
int chain_team_size(int beads) {
  constexpr bool host =
      Kokkos::SpaceAccessibility<Kokkos::HostSpace, typename Space::memory_space>::accessible;
  if (host) return 1;  // a thread sweeps its own chain: no barriers between threads
  return beads < 128 ? 32 : 128;
}

// All contact forces of realization r from u (one team). The two end contacts (walls or
// the ring's closing contact) are peeled off so the interior loop has no branches and
// vectorizes.
template <ChainForce Law, class Member, class Field, class Flags>
KOKKOS_INLINE_FUNCTION void chain_contact_pass(const Member& team, int r, int N, int C,
                                               bool periodic, const Field& u, const Field& kappa,
                                               const Field& delta0, const Field& klin,
                                               const Field& force, const Flags& opened) {
  int open = 0;
  Kokkos::parallel_reduce(
      Kokkos::TeamThreadRange(team, 1, N),
      [&](const int c, int& o) {
        double overlap;
        force(r, c) = ChainContactForce<Law>::eval(kappa(r, c), delta0(r, c), klin(r, c),
                                                   u(r, c - 1) - u(r, c), overlap);
        o += overlap > 0.0 ? 0 : 1;  // also counts NaN
      },
      open);
  Kokkos::single(Kokkos::PerTeam(team), [&]() {
    double overlap;
    force(r, 0) = ChainContactForce<Law>::eval(kappa(r, 0), delta0(r, 0), klin(r, 0),
                                               (periodic ? u(r, N - 1) : 0.0) - u(r, 0), overlap);
    int o = overlap > 0.0 ? 0 : 1;
    if (C > N) {
      force(r, N) =
          ChainContactForce<Law>::eval(kappa(r, N), delta0(r, N), klin(r, N), u(r, N - 1), overlap);
      o += overlap > 0.0 ? 0 : 1;
    }
    if (o + open > 0) opened(r) = 1;
  });
  team.team_barrier();
}

// a_i from the contact forces, then v += kick a, u += drift v. Bead N-1 of a ring takes
// its right force from contact 0; every other bead from contact i + 1.
template <class Member, class Field>
KOKKOS_INLINE_FUNCTION void chain_kick_drift_pass(const Member& team, int r, int N, int C,
                                                  double kick, double drift, const Field& u,
                                                  const Field& v, const Field& a, const Field& b,
                                                  const Field& force) {
  auto update = [&](const int i, const double f_right) {
    const double acc = (force(r, i) - f_right) / b(r, i);
    a(r, i) = acc;
    v(r, i) += kick * acc;
    u(r, i) += drift * v(r, i);
  };
  Kokkos::parallel_for(Kokkos::TeamThreadRange(team, 0, N - 1),
                       [&](const int i) { update(i, force(r, i + 1)); });
  Kokkos::single(Kokkos::PerTeam(team), [&]() { update(N - 1, force(r, N == C ? 0 : N)); });
  team.team_barrier();
}

// `steps` Verlet steps of every realization in one kernel; steps = 0 only computes the
// accelerations of the current displacements (after setting initial conditions).
template <ChainForce Law, class Space>
void chain_sweep(ChainBatch<Space>& c, double dt, long steps) {
  const int N = c.N, C = c.C;
  const bool periodic = c.spec.boundary == ChainBoundary::Periodic;
  auto u = c.u, v = c.v, a = c.a, b = c.b, kappa = c.kappa, delta0 = c.delta0, klin = c.klin,
       force = c.force;
  auto opened = c.opened;
  using Policy = Kokkos::TeamPolicy<Space>;
  using Member = typename Policy::member_type;
  const double h = 0.5 * dt;
  Kokkos::parallel_for(
      "chain::verlet", Policy(c.R, chain_team_size<Space>(N)), KOKKOS_LAMBDA(const Member& team) {
        const int r = team.league_rank();
        if (steps == 0) {
          chain_contact_pass<Law>(team, r, N, C, periodic, u, kappa, delta0, klin, force, opened);
          chain_kick_drift_pass(team, r, N, C, 0.0, 0.0, u, v, a, b, force);  // a only
          return;
        }
        // Half kick and drift: v(t + dt/2), u(t + dt).
        Kokkos::parallel_for(Kokkos::TeamThreadRange(team, N), [&](const int i) {
          v(r, i) += h * a(r, i);
          u(r, i) += dt * v(r, i);
        });
        team.team_barrier();
        for (long s = 1; s <= steps; ++s) {
          chain_contact_pass<Law>(team, r, N, C, periodic, u, kappa, delta0, klin, force, opened);
          // Full kick + drift in the interior of the run, half kick at its end so that
          // u, v and a are synchronized whenever control returns to the host.
          const double kick = s < steps ? dt : h;
          const double drift = s < steps ? dt : 0.0;
          chain_kick_drift_pass(team, r, N, C, kick, drift, u, v, a, b, force);
        }
      });
}

// Throws PhysicsError naming the first realization whose contact opened (or went NaN).
template <class Space>
void chain_check_contacts(ChainBatch<Space>& c, double t_from) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), c.opened);
  for (int r = 0; r < c.R; ++r)
    if (h(r)) {
      std::ostringstream msg;
      msg << "a contact of chain realization " << c.realization[r] << " opened (or became NaN) "
          << "between t = " << t_from << " and t = " << c.time
          << ": the wave amplitude is too large for the static pre-compression (the model "
             "holds only while every contact stays closed). Reduce the initial amplitude "
             "(v0 or u0) or the time step.";
      throw PhysicsError(msg.str());
    }
}

template <class Space>
void chain_accelerations(ChainBatch<Space>& c) {
  if (c.spec.force == ChainForce::Hertz)
    chain_sweep<ChainForce::Hertz>(c, 0.0, 0);
  else
    chain_sweep<ChainForce::Linear>(c, 0.0, 0);
  chain_check_contacts(c, c.time);
}

// The batch's kernel choice (ChainKernel): on chip where asked, or by default on a device
// where the chain fits one team; the global sweep otherwise. Asked for and not fitting is
// an error rather than a silent fall-back, so a benchmark measures what it names.
template <ChainForce Law, class Space>
void chain_step_with(ChainBatch<Space>& c, double dt, long steps) {
  constexpr bool host =
      Kokkos::SpaceAccessibility<Kokkos::HostSpace, typename Space::memory_space>::accessible;
  const bool try_chip = c.kernel == ChainKernel::OnChip || (c.kernel == ChainKernel::Auto && !host);
  if (try_chip && chain_advance_on_chip<Law>(c, dt, steps)) return;
  if (c.kernel == ChainKernel::OnChip)
    throw InputError("the on-chip chain kernel cannot hold a chain of " + std::to_string(c.N) +
                     " beads in one team of this execution space (it takes up to 32 beads per "
                     "thread of the largest team on a device, 4096 on a host); use the global "
                     "kernel");
  chain_sweep<Law>(c, dt, steps);
}

// Advances every realization by `steps` Verlet steps of size dt; u, v, a synchronized on
// return. A contact that opened stops the run.
template <class Space>
void chain_advance(ChainBatch<Space>& c, double dt, long steps) {
  if (steps <= 0) return;
  const double t0 = c.time;
  if (c.spec.force == ChainForce::Hertz)
    chain_step_with<ChainForce::Hertz>(c, dt, steps);
  else
    chain_step_with<ChainForce::Linear>(c, dt, steps);
  c.time = t0 + dt * static_cast<double>(steps);
  chain_check_contacts(c, t0);
}

}  // namespace granular
