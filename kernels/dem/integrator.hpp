// Velocity Verlet, split in its two half kicks. The first pass also drifts, re-enters
// particles through periodic faces and returns the largest squared displacement since
// the last neighbour build (fused so positions are read once per step).
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "kernels/cpu/host_simd.hpp"
#include "kernels/cpu/particle_pack.hpp"

namespace granular {

// Rotations are integrated only when the contact model produces torques.
// `pending`: the closing half kick of the previous step was deferred to this pass (one sweep
// over the particles instead of two); it is applied first, with the same roundings as a
// separate kick, so the trajectory is bitwise the same.
// `damp`: the pass also starts the next force sum, f = -gamma_b v and torque = -gamma_br w
// with the new velocities (what the force pass would otherwise set in a sweep of its own,
// same arithmetic); the force pass is then told that the sums are started.
struct DampingStart {
  bool on = false;
  double translational = 0.0, rotational = 0.0;
};

// The pass over particles i0 .. i1 - 1 for host backends, with raw pointers and the box in
// locals: the Kokkos loop kept its running maximum in memory and reloaded the box's fields
// after every store (the stores could alias them as far as the compiler knew). The same
// operations in the same order as the loop of kick_drift below, so the same bits; returns
// the block's largest squared displacement (NaNs skipped, as there).
// `pack`: where not null, the pass also writes each particle's packed record (ParticlePack in
// kernels/cpu/particle_pack.hpp: x, y, z, radius | vx, vy, vz, mass | wx, wy, wz, 0) with the
// values it has just stored, for the frictional stream of the force pass that follows.
struct KickDriftRows {
  double *x, *v, *f, *w, *q;
  const double *mass, *inertia, *x_ref;
  PeriodicBox box;
  double dt;
  bool pending;
  DampingStart damp;
  double* pack = nullptr;
  const double* radius = nullptr;  // read where pack is written

  // One component's kicks: the deferred closing half kick of the previous step (pend), this
  // step's opening one, and the next force sum started with the new velocity (start, mg =
  // -gamma). Returns the new velocity.
  KOKKOS_FORCEINLINE_FUNCTION static double kicks(double& vel, double& force, double h, bool pend,
                                                  bool start, double mg) {
    const double fd = force;
    const double v0 = pend ? vel + h * fd : vel;
    const double vd = v0 + h * fd;
    vel = vd;
    if (start) force = mg * vd;
    return vd;
  }

  // `Speed`: the block's largest squared drift velocity also goes to max_v2 (NaN if any).
  template <bool Rotations, bool Speed>
  double run(int i0, int i1, double& max_v2) const {
    double* const xs = x;
    double* const vs = v;
    double* const fs = f;
    double* const ws = w;
    double* const qs = q;
    const double* const ms = mass;
    const double* const is = inertia;
    const double* const xr = x_ref;
    const double step = dt;
    const bool pend = pending, start = damp.on;
    const double gb = damp.translational, gr = damp.rotational;
    double lo[3], len[3];
    bool per[3];
    for (int d = 0; d < 3; ++d) lo[d] = box.lo[d], len[d] = box.len[d], per[d] = box.periodic[d];
    double m = Kokkos::reduction_identity<double>::max();
    double mv = max_v2;
    for (int i = i0; i < i1; ++i) {
      const double h = 0.5 * step / ms[i];
      double d2 = 0.0, v2 = 0.0;
      for (int d = 0; d < 3; ++d) {
        const double vd = kicks(vs[3 * i + d], fs[3 * i + d], h, pend, start, -gb);
        double xd = xs[3 * i + d] + step * vd;
        if (per[d]) {  // PeriodicBox::wrap
          if (xd >= lo[d] + len[d])
            xd -= len[d];
          else if (xd < lo[d])
            xd += len[d];
        }
        xs[3 * i + d] = xd;
        double u = xd - xr[3 * i + d];
        if (per[d]) {  // PeriodicBox::min_image
          if (u > 0.5 * len[d])
            u -= len[d];
          else if (u < -0.5 * len[d])
            u += len[d];
        }
        d2 += u * u;
        if (Speed) v2 += vd * vd;
      }
      if (Rotations) {
        const double hr = 0.5 * step / is[i];
        for (int d = 0; d < 3; ++d) kicks(ws[3 * i + d], qs[3 * i + d], hr, pend, start, -gr);
      }
      m = d2 > m ? d2 : m;
      // NaN counts as a move beyond any skin here: the near list is then recorded again.
      if (Speed) mv = v2 > mv || v2 != v2 ? v2 : mv;
      if (pack != nullptr) write_record(i);
    }
    max_v2 = mv;
    return m;
  }
  // Particle i's packed record from the arrays.
  void write_record(int i) const {
    double* const r = pack + static_cast<long>(ParticlePack::kStride) * i;
    for (int d = 0; d < 3; ++d)
      r[d] = x[3 * i + d], r[4 + d] = v[3 * i + d], r[8 + d] = w[3 * i + d];
    r[3] = radius[i], r[7] = mass[i], r[11] = 0.0;
  }

#if GRANULAR_HOST_AVX
  // run() four particles (twelve components) at a time in AVX2 registers, where the processor
  // has AVX2: the same operations per component, branches replaced by selecting between both
  // outcomes, the squared sums per particle in run()'s order, so the same bits; the particles
  // after the last whole four go through run().
  using V4 = simd4::V;
  using M4 = simd4::M;
  // kicks() on four components at vel and force.
  GRANULAR_AVX2_INLINE static V4 kicks4(double* vel, double* force, V4 h, bool pend, bool start,
                                        V4 mg) {
    const V4 fd = simd4::load(force), v_old = simd4::load(vel);
    const V4 v0 = pend ? v_old + h * fd : v_old;
    const V4 vd = v0 + h * fd;
    simd4::store(vel, vd);
    if (start) simd4::store(force, mg * vd);
    return vd;
  }
  // Per-particle values of four particles spread over their twelve components (part k of 3).
  GRANULAR_AVX2_INLINE static V4 spread(V4 a, int k) {
    using I4 = long __attribute__((vector_size(32)));
    if (k == 0) return __builtin_shuffle(a, I4{0, 0, 0, 1});
    if (k == 1) return __builtin_shuffle(a, I4{1, 1, 2, 2});
    return __builtin_shuffle(a, I4{2, 3, 3, 3});
  }
  // Per-particle sums of the twelve components of four particles (a[k] holds components
  // 4 k .. 4 k + 3: x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3), in the order x + y + z.
  GRANULAR_AVX2_INLINE static V4 sum_by_particle(const V4 a[3]) {
    using I4 = long __attribute__((vector_size(32)));
    const V4 x =
        __builtin_shuffle(__builtin_shuffle(a[0], a[1], I4{0, 3, 6, 6}), a[2], I4{0, 1, 2, 5});
    const V4 y =
        __builtin_shuffle(__builtin_shuffle(a[0], a[1], I4{1, 4, 7, 7}), a[2], I4{0, 1, 2, 6});
    const V4 z =
        __builtin_shuffle(__builtin_shuffle(a[0], a[1], I4{2, 5, 5, 5}), a[2], I4{0, 1, 4, 7});
    return (x + y) + z;
  }
  // The twelve components of four particles (a[k]: components 4 k .. 4 k + 3) stored as four
  // quarters of packed records, particle p's (c_x, c_y, c_z, e[p]) at out + S p.
  GRANULAR_AVX2_INLINE static void store_quarters(double* out, const V4 a[3], V4 e) {
    constexpr int S = ParticlePack::kStride;
    using I4 = long __attribute__((vector_size(32)));
    const V4 t1 = __builtin_shuffle(a[0], a[1], I4{3, 4, 5, 5});
    const V4 t2 = __builtin_shuffle(a[1], a[2], I4{2, 3, 4, 4});
    simd4::store(out, __builtin_shuffle(a[0], e, I4{0, 1, 2, 4}));
    simd4::store(out + S, __builtin_shuffle(t1, e, I4{0, 1, 2, 5}));
    simd4::store(out + 2 * S, __builtin_shuffle(t2, e, I4{0, 1, 2, 6}));
    simd4::store(out + 3 * S, __builtin_shuffle(a[2], e, I4{1, 2, 3, 7}));
  }
  template <bool Rotations, bool Speed>
  GRANULAR_AVX2 double run_avx2(int i0, int i1, double& max_v2) const {
    const double step = dt;
    const bool pend = pending, start = damp.on;
    // The box's per-component constants in the same twelve-component pattern (d = c % 3).
    V4 hi[3], lo4[3], len4[3], half4[3];
    M4 per4[3];
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 4; ++c) {
        const int d = (4 * k + c) % 3;
        hi[k][c] = box.lo[d] + box.len[d], lo4[k][c] = box.lo[d], len4[k][c] = box.len[d];
        half4[k][c] = 0.5 * box.len[d];
        per4[k][c] = box.periodic[d] ? -1 : 0;
      }
    const V4 half_step = simd4::splat(0.5 * step), vstep = simd4::splat(step);
    const V4 mgb = simd4::splat(-damp.translational), mgr = simd4::splat(-damp.rotational);
    // Running maxima per lane (lane p: particles i0 + p, i0 + p + 4, ...), combined at the
    // end: a maximum with NaNs skipped (m) or kept (mv) is the same in any order.
    V4 m4 = simd4::splat(Kokkos::reduction_identity<double>::max()), mv4 = simd4::splat(max_v2);
    int i = i0;
    double* const pk = pack;
    const V4 zero = simd4::splat(0.0);
    for (; i + 4 <= i1; i += 4) {
      const V4 h4 = half_step / simd4::load(mass + i);
      V4 uu[3], vv[3], xs[3], vs[3], ws[3];
      for (int k = 0; k < 3; ++k) {
        const int o = 3 * i + 4 * k;
        const V4 vd = kicks4(v + o, f + o, spread(h4, k), pend, start, mgb);
        vs[k] = vd;
        V4 xd = simd4::load(x + o) + vstep * vd;
        const M4 above = per4[k] & (xd >= hi[k]), below = per4[k] & (xd < lo4[k]);
        xd = above ? xd - len4[k] : (below ? xd + len4[k] : xd);  // PeriodicBox::wrap
        simd4::store(x + o, xd);
        xs[k] = xd;
        V4 u = xd - simd4::load(x_ref + o);
        const M4 far = per4[k] & (u > half4[k]), near = per4[k] & (u < -half4[k]);
        u = far ? u - len4[k] : (near ? u + len4[k] : u);  // PeriodicBox::min_image
        uu[k] = u * u;
        if (Speed) vv[k] = vd * vd;
      }
      if (Rotations) {
        const V4 hr4 = half_step / simd4::load(inertia + i);
        for (int k = 0; k < 3; ++k) {
          const int o = 3 * i + 4 * k;
          ws[k] = kicks4(w + o, q + o, spread(hr4, k), pend, start, mgr);
        }
      } else if (pk != nullptr) {  // the spins as they are
        for (int k = 0; k < 3; ++k) ws[k] = simd4::load(w + 3 * i + 4 * k);
      }
      if (pk != nullptr) {
        double* const r = pk + static_cast<long>(ParticlePack::kStride) * i;
        store_quarters(r + ParticlePack::kPosRadius, xs, simd4::load(radius + i));
        store_quarters(r + ParticlePack::kVelocity, vs, simd4::load(mass + i));
        store_quarters(r + ParticlePack::kSpin, ws, zero);
      }
      // run()'s sums per particle, (0 + a_x) + a_y + a_z, in lanes: 0 + a is a for every
      // square (never -0), so (a_x + a_y) + a_z.
      const V4 d2 = sum_by_particle(uu);
      m4 = d2 > m4 ? d2 : m4;
      if (Speed) {
        const V4 v2 = sum_by_particle(vv);
        mv4 = (v2 > mv4) | (v2 != v2) ? v2 : mv4;
      }
    }
    double m = m4[0], mv = mv4[0];
    for (int p = 1; p < 4; ++p) {
      m = m4[p] > m ? m4[p] : m;
      mv = mv4[p] > mv || mv4[p] != mv4[p] ? mv4[p] : mv;
    }
    max_v2 = mv;
    const double tail = run<Rotations, Speed>(i, i1, max_v2);
    return tail > m ? tail : m;
  }
#endif
};

// The largest squared drift velocity of a kick_drift pass (host backends), which bounds how
// far any particle moved (DemSystem's near list, NearRows in kernels/dem/contact_forces.hpp).
struct DriftSpeed {
  double max_v2 = 0.0;
  std::vector<double> block;  // per block of the pass (kept: no allocation per step)
};

// kick_drift's pass for devices, one particle per call, folding its squared displacement
// into the running maximum m. A functor, not a lambda: written as a KOKKOS_LAMBDA, its
// launch called a null pointer on an H200 (CUDA 13) in some tests and not in others. nvcc
// gives the wrapper of a host-device lambda a copy helper private to each translation unit;
// where the function template holding the lambda is instantiated in several units, the
// linker can pair the wrapper's code from one unit with another's helper, left null. An
// ordinary class has no such helper.
template <bool Rotations, class ExecSpace>
struct KickDriftPass {
  typename Particles<ExecSpace>::vec_view x, v, f, w, q, x_ref;
  typename Particles<ExecSpace>::scalar_view mass, inertia;
  PeriodicBox b;
  double dt, gb, gr;
  bool pending, start;
  KOKKOS_INLINE_FUNCTION void operator()(const int i, double& m) const {
    const double h = 0.5 * dt / mass(i);
    double d2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      const double v0 = pending ? v(i, d) + h * f(i, d) : v(i, d);
      const double vd = v0 + h * f(i, d);
      v(i, d) = vd;
      if (start) f(i, d) = -gb * vd;
      const double xd = b.wrap(x(i, d) + dt * vd, d);
      x(i, d) = xd;
      const double u = b.min_image(xd - x_ref(i, d), d);
      d2 += u * u;
    }
    if (Rotations) {
      const double hr = 0.5 * dt / inertia(i);
      for (int d = 0; d < 3; ++d) {
        const double w0 = pending ? w(i, d) + hr * q(i, d) : w(i, d);
        const double wd = w0 + hr * q(i, d);
        w(i, d) = wd;
        if (start) q(i, d) = -gr * wd;
      }
    }
    m = d2 > m ? d2 : m;
  }
};

// The pass above over every particle (any backend runs it: tests compare it with the host
// rows). A team reduction (a block per 128 particles, where Kokkos' range reduction launches
// at most 256 blocks on a device) was slower on an H200: 182 against 121 us per step at
// N = 1M (docs/perf_design_notes.md, GPU).
template <bool Rotations, class ExecSpace>
double kick_drift_kokkos(const Particles<ExecSpace>& p, const PeriodicBox& box,
                         const typename Particles<ExecSpace>::vec_view& x_ref, double dt,
                         bool pending, DampingStart damp) {
  const KickDriftPass<Rotations, ExecSpace> pass{
      p.x,     p.v,       p.f, p.w, p.torque,           x_ref,
      p.mass,  p.inertia, box, dt,  damp.translational, damp.rotational,
      pending, damp.on};
  double max_sq = 0.0;
  Kokkos::parallel_reduce("dem::VelocityVerlet::kick_drift", Kokkos::RangePolicy<ExecSpace>(0, p.n),
                          pass, Kokkos::Max<double>(max_sq));
  return max_sq;
}

template <bool Rotations, class ExecSpace>
double kick_drift(const Particles<ExecSpace>& p, const PeriodicBox& box,
                  const typename Particles<ExecSpace>::vec_view& x_ref, double dt,
                  bool pending = false, DampingStart damp = DampingStart(),
                  DriftSpeed* speed = nullptr, double* pack = nullptr) {
  if constexpr (std::is_same_v<typename ExecSpace::memory_space, Kokkos::HostSpace>) {
    const KickDriftRows rows{p.x.data(),
                             p.v.data(),
                             p.f.data(),
                             p.w.data(),
                             p.torque.data(),
                             p.mass.data(),
                             p.inertia.data(),
                             x_ref.data(),
                             box,
                             dt,
                             pending,
                             damp,
                             pack,
                             p.radius.data()};
    constexpr int kBlock = 512;  // particles per task
    const int n = p.n, blocks = (n + kBlock - 1) / kBlock;
#if GRANULAR_HOST_AVX
    const bool avx2 = cpu_has_avx2();
#endif
    // Block bk of the pass, in AVX2 where the processor has it (the same bits).
    auto block = [=](auto speed_tag, int bk, double& v2) {
      constexpr bool Speed = decltype(speed_tag)::value;
      const int i0 = bk * kBlock, i1 = std::min(n, i0 + kBlock);
#if GRANULAR_HOST_AVX
      if (avx2) return rows.run_avx2<Rotations, Speed>(i0, i1, v2);
#endif
      return rows.run<Rotations, Speed>(i0, i1, v2);
    };
    double max_sq = 0.0;
    if (speed == nullptr) {
      Kokkos::parallel_reduce(
          "dem::VelocityVerlet::kick_drift_rows", Kokkos::RangePolicy<ExecSpace>(0, blocks),
          [=](const int bk, double& m) {
            double unused = 0.0;
            const double mb = block(std::false_type(), bk, unused);
            m = mb > m ? mb : m;
          },
          Kokkos::Max<double>(max_sq));
      return max_sq;
    }
    // Both maxima: the blocks' speeds go to a per-block array, reduced after (a maximum is
    // exact in any order).
    speed->block.assign(blocks, 0.0);
    double* const bs = speed->block.data();
    Kokkos::parallel_reduce(
        "dem::VelocityVerlet::kick_drift_rows_speed", Kokkos::RangePolicy<ExecSpace>(0, blocks),
        [=](const int bk, double& m) {
          const double mb = block(std::true_type(), bk, bs[bk]);
          m = mb > m ? mb : m;
        },
        Kokkos::Max<double>(max_sq));
    double mv = 0.0;
    for (int bk = 0; bk < blocks; ++bk) mv = bs[bk] > mv || bs[bk] != bs[bk] ? bs[bk] : mv;
    speed->max_v2 = mv;
    return max_sq;
  }
  if (pack != nullptr)  // the packed records serve the host force pass only
    throw std::logic_error("kick_drift: packed records are written on host backends only");
  return kick_drift_kokkos<Rotations>(p, box, x_ref, dt, pending, damp);
}

template <bool Rotations, class ExecSpace>
void kick(const Particles<ExecSpace>& p, double dt) {
  auto v = p.v, f = p.f, w = p.w, q = p.torque;
  auto mass = p.mass, inertia = p.inertia;
  Kokkos::parallel_for(
      "dem::VelocityVerlet::kick", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i) {
        const double h = 0.5 * dt / mass(i);
        v(i, 0) += h * f(i, 0);
        v(i, 1) += h * f(i, 1);
        v(i, 2) += h * f(i, 2);
        if (Rotations) {
          const double hr = 0.5 * dt / inertia(i);
          for (int d = 0; d < 3; ++d) w(i, d) += hr * q(i, d);
        }
      });
}

// Brings every particle into the primary box (any distance outside it).
template <class ExecSpace>
void wrap_positions(const Particles<ExecSpace>& p, const PeriodicBox& box) {
  auto x = p.x;
  const PeriodicBox b = box;
  Kokkos::parallel_for(
      "dem::wrap_positions", Kokkos::RangePolicy<ExecSpace>(0, p.n), KOKKOS_LAMBDA(const int i) {
        for (int d = 0; d < 3; ++d) {
          if (!b.periodic[d]) continue;
          const double l = b.len[d];
          const double xd = x(i, d) - l * Kokkos::Experimental::floor((x(i, d) - b.lo[d]) / l);
          x(i, d) = xd < b.lo[d] + l ? xd : b.lo[d];  // round-off can land exactly on the face
        }
      });
}

}  // namespace granular
