// Velocity Verlet with each realization held on chip for all the steps of one call
// (docs/model_chains.md, "Kernels"). One team per realization; thread t of the team owns the
// B consecutive beads t*B .. t*B+B-1 and keeps their displacement, velocity, mass and
// left-contact parameters in registers (thread-private arrays of compile-time size). A step
// exchanges only the two end displacements of every thread, through a double-buffered
// halo in team scratch memory: one barrier per step, and no global memory traffic between
// the loading of the chain and the writing back of u, v and a.
//
// The global sweep (chain_verlet.hpp) computes each contact force once and reads it for
// both of its beads; here the contact between two threads' blocks is computed by both, from
// the same two displacements and the same parameters, so both kernels produce the same bits
// (tests/kernels/chain/test_chain_on_chip.cpp).
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>

#include "kernels/chain/chain_batch.hpp"
#include "kernels/chain/chain_contact_force.hpp"

namespace granular {

// One team's chain: its registers and the step, for B beads per thread.
template <ChainForce Law, int B>
struct ChainOnChipThread {
  double u[B], v[B], b[B];
  double p[B], d[B];  // left contact of each bead: kappa (Hertz) or klin (linear), and delta0
  double p_right = 0.0, d_right = 0.0;  // the contact right of the last owned bead
  int n = 0;                            // beads owned (the last thread may own fewer than B)
  int open = 0;                         // a contact was found open (or NaN)

  KOKKOS_INLINE_FUNCTION double force(double pc, double dc, double du) {
    double overlap;
    const double f = ChainContactForce<Law>::eval(pc, dc, pc, du, overlap);
    open |= overlap > 0.0 ? 0 : 1;  // also catches NaN
    return f;
  }

  KOKKOS_INLINE_FUNCTION double last_u() const {
    double x = u[0];
    for (int j = 1; j < B; ++j)
      if (j < n) x = u[j];
    return x;
  }

  // Forces of the owned beads' left contacts (f) and of the last one's right contact
  // (f_right), given the displacement left of the first bead and right of the last. At a
  // fixed wall the global sweep forms du as 0 - u_0 and as u_{N-1}: `wall_left` and
  // `wall_right` keep those exact expressions.
  KOKKOS_INLINE_FUNCTION void forces(double u_left, double u_right, bool wall_left, bool wall_right,
                                     double (&f)[B], double& f_right) {
    f[0] = force(p[0], d[0], (wall_left ? 0.0 : u_left) - u[0]);
    for (int j = 1; j < B; ++j) f[j] = j < n ? force(p[j], d[j], u[j - 1] - u[j]) : 0.0;
    const double ul = last_u();
    f_right = force(p_right, d_right, wall_right ? ul : ul - u_right);
  }

  // a = (f_left - f_right) / b, v += kick a, u += drift v; a is written out only when asked.
  template <class Field>
  KOKKOS_INLINE_FUNCTION void kick_drift(const double (&f)[B], double f_right, double kick,
                                         double drift, bool store, const Field& a, int r, int i0) {
    for (int j = 0; j < B; ++j)
      if (j < n) {
        // j + 1 < n implies j + 1 < B (n <= B); the inner bound only keeps the unrolled
        // index of the last lane inside the array.
        const double fr = j + 1 < n ? f[j + 1 < B ? j + 1 : j] : f_right;
        const double acc = (f[j] - fr) / b[j];
        v[j] += kick * acc;
        u[j] += drift * v[j];
        if (store) a(r, i0 + j) = acc;
      }
  }
};

// The largest team of this space for `body`. Asked of a one-thread policy (constructing one
// with too large a team aborts), and capped by the space's threads: Kokkos 3.4's OpenMP
// answers from a count of threads that can exceed the pool it then checks the request against.
template <class Space, class Body>
int chain_team_max(const Body& body) {
  const int max = Kokkos::TeamPolicy<Space>(1, 1).team_size_max(body, Kokkos::ParallelForTag());
  return std::min(max, Space().concurrency());
}

// Whether B beads per thread are worth trying here: thread-private arrays of more than 32
// doubles would spill out of a device's registers.
template <int B, class Space>
constexpr bool chain_on_chip_block_allowed() {
  return B <= 32 ||
         Kokkos::SpaceAccessibility<Kokkos::HostSpace, typename Space::memory_space>::accessible;
}

// `steps` (> 0) Verlet steps of every realization with B beads per thread. Returns false,
// running nothing, where ceil(N / B) threads do not fit one team of this space.
template <ChainForce Law, int B, class Space>
bool chain_sweep_on_chip(ChainBatch<Space>& c, double dt, long steps) {
  if constexpr (!chain_on_chip_block_allowed<B, Space>()) {
    (void)c, (void)dt, (void)steps;
    return false;
  } else {
    const int N = c.N, C = c.C, T = (N + B - 1) / B;
    const bool periodic = c.spec.boundary == ChainBoundary::Periodic;
    auto U = c.u, V = c.v, A = c.a, M = c.b, D = c.delta0;
    auto P = Law == ChainForce::Hertz ? c.kappa : c.klin;
    auto opened = c.opened;
    using Policy = Kokkos::TeamPolicy<Space>;
    using Member = typename Policy::member_type;
    using Halo = Kokkos::View<double*, typename Space::scratch_memory_space,
                              Kokkos::MemoryTraits<Kokkos::Unmanaged>>;
    const int halo_size = 4 * T;  // two buffers of (first u, last u) per thread
    const double h = 0.5 * dt;
    auto body = KOKKOS_LAMBDA(const Member& team) {
      const int r = team.league_rank(), t = team.team_rank(), i0 = t * B;
      Halo halo(team.team_scratch(0), halo_size);
      ChainOnChipThread<Law, B> th;
      th.n = N - i0 < B ? N - i0 : B;
      for (int j = 0; j < B; ++j) {
        const bool own = j < th.n;
        th.u[j] = own ? U(r, i0 + j) : 0.0;
        th.v[j] = own ? V(r, i0 + j) : 0.0;
        th.b[j] = own ? M(r, i0 + j) : 1.0;
        th.p[j] = own ? P(r, i0 + j) : 0.0;
        th.d[j] = own ? D(r, i0 + j) : 0.0;
        // Half kick and drift: v(t + dt/2), u(t + dt).
        if (own) {
          th.v[j] += h * A(r, i0 + j);
          th.u[j] += dt * th.v[j];
        }
      }
      const int cr = i0 + th.n < N ? i0 + th.n : (C > N ? N : 0);
      th.p_right = P(r, cr), th.d_right = D(r, cr);
      const bool first = t == 0, last = t == T - 1;
      for (long s = 1; s <= steps; ++s) {
        const int buf = static_cast<int>(s & 1) * 2 * T;
        halo(buf + t) = th.u[0];
        halo(buf + T + t) = th.last_u();
        team.team_barrier();
        // Bead N-1 (the last thread's last) is left of bead 0 in a ring; bead 0 right of N-1.
        const double u_left =
            first ? (periodic ? halo(buf + T + T - 1) : 0.0) : halo(buf + T + t - 1);
        const double u_right = last ? (periodic ? halo(buf) : 0.0) : halo(buf + t + 1);
        double f[B], f_right;
        th.forces(u_left, u_right, first && !periodic, last && !periodic, f, f_right);
        // Full kick + drift in the interior of the run, half kick at its end so that
        // u, v and a are synchronized whenever control returns to the host.
        const bool end = s == steps;
        th.kick_drift(f, f_right, end ? h : dt, end ? 0.0 : dt, end, A, r, i0);
      }
      for (int j = 0; j < B; ++j)
        if (j < th.n) U(r, i0 + j) = th.u[j], V(r, i0 + j) = th.v[j];
      if (th.open) Kokkos::atomic_exchange(&opened(r), 1);
    };
    if (T > chain_team_max<Space>(body) ||
        Halo::shmem_size(halo_size) > static_cast<size_t>(Policy::scratch_size_max(0)))
      return false;
    Policy policy(c.R, T);
    policy.set_scratch_size(0, Kokkos::PerTeam(Halo::shmem_size(halo_size)));
    Kokkos::parallel_for("chain::verlet_on_chip", policy, body);
    return true;
  }
}

// The smallest B in 4, 8, ..., 4096 whose team fits (the most threads per chain); false
// where none does. B above 32 only on host spaces (see chain_on_chip_block_allowed).
template <ChainForce Law, class Space>
bool chain_advance_on_chip(ChainBatch<Space>& c, double dt, long steps) {
  return chain_sweep_on_chip<Law, 4>(c, dt, steps) || chain_sweep_on_chip<Law, 8>(c, dt, steps) ||
         chain_sweep_on_chip<Law, 16>(c, dt, steps) || chain_sweep_on_chip<Law, 32>(c, dt, steps) ||
         chain_sweep_on_chip<Law, 256>(c, dt, steps) ||
         chain_sweep_on_chip<Law, 4096>(c, dt, steps);
}

}  // namespace granular
