// The near list as one flat stream of contacts per slab, for the host one-pass force kernel
// with the batched frictional laws (linear, the Hertz-Mindlin laws, hysteretic) and
// with the frictionless linear law (kernels/dem/contact_forces.hpp,
// kernels/cpu/contact_batch.hpp).
//
// The batched rows split each owner row into its touching entries, copy the touching pairs'
// positions, velocities, spins and springs into the batch's slots, evaluate them four at a
// time and scatter the forces row by row: three loops per row whose lengths (0 to ~6
// entries) the branch predictor cannot follow, and a copy of every input through memory.
// While the near list is read, its entries do not change: a recording writes them once as
// a stream (owner, partner, history row, in the slabs' row order), and the force passes that
// read it take four consecutive entries at a time, whatever rows they belong to, load
// their inputs straight into AVX registers from the particle arrays, test the distance and
// evaluate the law in the lanes, then scatter lane by lane in stream order. The sums are
// formed in the batched rows' order (each contact's reaction when its row is reached, each
// owner's own sum at its row's end), an apart entry forgets its spring as there, and every
// lane performs the batched law's operations, so the results are bitwise those of the rows.
//
// Rows without near entries add their (zero) sum too: adding +0 to a chain of additions
// changes its result only where the whole chain is -0, wherever in the chain it is added, so
// these rows add it before the slab's stream is read.
//
// Where the step supplies them, the frictional stream reads each particle's position, radius,
// velocity and spin from one packed record (kernels/cpu/particle_pack.hpp), written by the step's
// kick-drift pass from the values it has just stored: a partner then costs two cache lines of
// input instead of four, and each quarter of a record comes in with the quarters of three
// other particles as four aligned loads transposed in registers. The values, and so the bits,
// are those of the arrays (gains: docs/perf_design_notes.md; the frictionless stream gained
// nothing).
//
// The frictionless linear law reads the stream as well (near_stream_slab_normal): its rows
// are evaluated contact by contact, not batched, but they pay the same loop per row of
// unpredictable length and a dependent load of the partner's index through the list. An
// earlier form that gathered every input lane by lane gained nothing (0.99x); with the
// loads and the paired scatter of the frictional stream it gains 1.13-1.19x
// (docs/perf_design_notes.md).
#pragma once
#include <Kokkos_Core.hpp>
#include <type_traits>
#include <vector>

#include "core/dem/box.hpp"
#include "kernels/cpu/contact_batch.hpp"
#include "kernels/cpu/host_rows.hpp"
#include "kernels/cpu/particle_pack.hpp"

#if GRANULAR_CONTACT_BATCH
#include <immintrin.h>
#endif

namespace granular {

// The stream of one recording of the near list: entry e joins owner i[e] with partner j[e],
// history row r[e] (empty for a law without history); slab s's entries are begin[s] .. begin[s + 1]
// - 1 and its rows without a near entry are empty[empty_begin[s]] .. empty[empty_begin[s + 1] - 1].
// Four entries of valid indices follow the last one (gathered by the last vector, never scattered).
struct NearStream {
  std::vector<int> i, j, r, begin, empty, empty_begin;
  // Whether the last force pass recorded it (the next ones may read it).
  bool ready = false;
  long reads = 0;         // force passes that read it
  long packed_reads = 0;  // those of them that read the particles' packed records
  // Frees the arrays (a neighbour rebuild invalidates them; the count of reads stays).
  void release() {
    for (std::vector<int>* a : {&i, &j, &r, &begin, &empty, &empty_begin})
      std::vector<int>().swap(*a);
    ready = false;
  }
};

// Whether 3 * index stays an int for every history row and particle (the loads' offsets; the
// hysteretic law's rows of four are offset in long).
inline bool near_stream_indexable(long rows, long particles) {
  return 3 * rows < 2147483647L && 3 * particles < 2147483647L;
}

#if GRANULAR_CONTACT_BATCH

// The frictionless linear law, which the stream evaluates in lanes of its own
// (near_stream_slab_normal; its rows evaluate it contact by contact, not in batches).
template <class Model>
inline constexpr bool is_frictionless_linear = std::is_same_v<Model, ContactModel<LinearNormal>>;

// Whether the stream can serve this model instance on this processor: the batched law, or
// the frictionless linear law, with one parameter set (broadcast; the lanes load no
// per-pair parameters), AVX2.
template <class Model>
bool near_stream_usable(const Model& m) {
  using Law = ContactBatchLaw<ContactModel<LinearNormal, CoulombTangential>>;
  if constexpr (is_frictionless_linear<Model>)
    return cpu_has_avx2() && Law::uniform_normal(m.normal);
  else if constexpr (ContactBatchLaw<Model>::available)
    return cpu_has_avx2() && ContactBatchLaw<Model>::usable(m) &&
           ContactBatchLaw<Model>::uniform(m);
  else
    return false;
}

// Writes the stream of the near list just recorded (nr) for the slabs of `list`; the
// history rows only where the law has a history (`rows`).
template <class ExecSpace>
void record_near_stream(NearStream& st, const HostListRows& list, const HostArray<const int>& order,
                        const HostArray<const int>& slab_begin, int slabs, const NearRows& nr,
                        bool rows = true) {
  using Policy = Kokkos::RangePolicy<ExecSpace>;
  st.begin.assign(slabs + 1, 0);
  st.empty_begin.assign(slabs + 1, 0);
  int* const sb = st.begin.data();
  int* const eb = st.empty_begin.data();
  Kokkos::parallel_for("dem::near_stream::count", Policy(0, slabs), [=](const int s) {
    int entries = 0, empty = 0;
    for (int q = slab_begin(s); q < slab_begin(s + 1); ++q) {
      const int c = nr.count[order(q)];
      entries += c;
      empty += c == 0;
    }
    sb[s + 1] = entries, eb[s + 1] = empty;
  });
  for (int s = 0; s < slabs; ++s) sb[s + 1] += sb[s], eb[s + 1] += eb[s];
  const size_t total = static_cast<size_t>(sb[slabs]) + ContactBatch::kW;
  // Grown with room to spare (recordings come every few steps), the old arrays released
  // first: their content is rewritten below, and holding both would raise the peak memory.
  auto grow = [&](std::vector<int>& a, bool used) {
    if (used && a.size() >= total) return;
    std::vector<int>().swap(a);
    if (used) a.resize(total + total / 8);
  };
  grow(st.i, true), grow(st.j, true), grow(st.r, rows);
  st.empty.resize(static_cast<size_t>(eb[slabs]));
  int* const si = st.i.data();
  int* const sj = st.j.data();
  int* const sr = rows ? st.r.data() : nullptr;
  int* const se = st.empty.data();
  Kokkos::parallel_for("dem::near_stream::record", Policy(0, slabs), [=](const int s) {
    int e = sb[s], z = eb[s];
    for (int q = slab_begin(s); q < slab_begin(s + 1); ++q) {
      const int i = order(q), pb = list.pair_begin(i), row0 = pb - list.offsets(i);
      const int c = nr.count[i];
      if (c == 0) se[z++] = i;
      for (int a = pb; a < pb + c; ++a, ++e) {
        const int k = nr.k[a];
        si[e] = i, sj[e] = list.neighbors(k);
        if (sr != nullptr) sr[e] = row0 + k;
      }
    }
  });
  // The padding: the first entry's particles and history row 0 (valid indices wherever there
  // is an entry; with none, no vector is read).
  for (int e = sb[slabs]; e < sb[slabs] + ContactBatch::kW; ++e) {
    si[e] = sb[slabs] > 0 ? si[0] : 0, sj[e] = sb[slabs] > 0 ? sj[0] : 0;
    if (sr != nullptr) sr[e] = 0;
  }
  st.ready = true;
}

namespace near_stream_detail {
using V = ContactBatch::V;
using M = ContactBatch::M;

// The 3-vectors base[3 k .. 3 k + 2] of the four particles (or history rows) k = idx[0..3],
// as three vectors of four lanes: two 16-byte loads of (x, y) joined into one register per
// pair of lanes, unpacked into x and y, and the four z joined alike. 1.02-1.04x against
// three gathers (docs/perf_design_notes.md, CPUs), the same values.
GRANULAR_AVX2_INLINE void load3(const double* base, const int* idx, V& X, V& Y, V& Z) {
  const double* const p0 = base + 3 * idx[0];
  const double* const p1 = base + 3 * idx[1];
  const double* const p2 = base + 3 * idx[2];
  const double* const p3 = base + 3 * idx[3];
  const __m256d a = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p0)), _mm_loadu_pd(p2),
                                         1);  // x0 y0 x2 y2
  const __m256d c = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p1)), _mm_loadu_pd(p3),
                                         1);  // x1 y1 x3 y3
  X = (V)_mm256_unpacklo_pd(a, c);
  Y = (V)_mm256_unpackhi_pd(a, c);
  const __m128d z01 = _mm_loadh_pd(_mm_load_sd(p0 + 2), p1 + 2);
  const __m128d z23 = _mm_loadh_pd(_mm_load_sd(p2 + 2), p3 + 2);
  Z = (V)_mm256_insertf128_pd(_mm256_castpd128_pd256(z01), z23, 1);
}
// Four rows of four doubles (r_l: lane l's values) as four vectors of lane l's values: A takes
// each row's first, D its last.
GRANULAR_AVX2_INLINE void transpose4(__m256d r0, __m256d r1, __m256d r2, __m256d r3, V& A, V& B,
                                     V& C, V& D) {
  const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
  const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
  A = (V)_mm256_permute2f128_pd(t0, t2, 0x20);
  B = (V)_mm256_permute2f128_pd(t1, t3, 0x20);
  C = (V)_mm256_permute2f128_pd(t0, t2, 0x31);
  D = (V)_mm256_permute2f128_pd(t1, t3, 0x31);
}
// The quarter `at` of the packed records (ParticlePack) of the four particles k = idx[0..3],
// as four vectors of four lanes (lane l: particle idx[l]): four aligned 32-byte loads and a
// 4 x 4 transpose.
GRANULAR_AVX2_INLINE void load_packed(const double* pack, int at, const int* idx, V& A, V& B, V& C,
                                      V& D) {
  constexpr long S = ParticlePack::kStride;
  transpose4(_mm256_load_pd(pack + S * idx[0] + at), _mm256_load_pd(pack + S * idx[1] + at),
             _mm256_load_pd(pack + S * idx[2] + at), _mm256_load_pd(pack + S * idx[3] + at), A, B,
             C, D);
}
// The 4-vectors base[4 k .. 4 k + 3] of the four history rows k = idx[0..3] (the hysteretic
// law's delta_max and spring), as four vectors of four lanes: four 32-byte loads and a 4 x 4
// transpose.
GRANULAR_AVX2_INLINE void load4(const double* base, const int* idx, V& A, V& B, V& C, V& D) {
  transpose4(_mm256_loadu_pd(base + 4L * idx[0]), _mm256_loadu_pd(base + 4L * idx[1]),
             _mm256_loadu_pd(base + 4L * idx[2]), _mm256_loadu_pd(base + 4L * idx[3]), A, B, C, D);
}
// base[k] of the four indices k = idx[0..3].
GRANULAR_AVX2_INLINE V load1(const double* base, const int* idx) {
  const __m128d a01 = _mm_loadh_pd(_mm_load_sd(base + idx[0]), base + idx[1]);
  const __m128d a23 = _mm_loadh_pd(_mm_load_sd(base + idx[2]), base + idx[3]);
  return (V)_mm256_insertf128_pd(_mm256_castpd128_pd256(a01), a23, 1);
}
// min_image_of on four lanes of a periodic axis: the same comparisons and the same one
// addition per lane. The box's length, half of it and its negative come splat once per slab.
GRANULAR_AVX2_INLINE V min_image4(V dx, V len, V hl, V nhl) {
  const V down = dx - len, up = dx + len;
  return ContactBatch::sel(dx > hl, down, ContactBatch::sel(dx < nhl, up, dx));
}
// a[0 .. 2] += (xy, z), component by component.
GRANULAR_AVX2_INLINE void add3(double* a, __m128d xy, double z) {
  _mm_storeu_pd(a, _mm_add_pd(_mm_loadu_pd(a), xy));
  a[2] += z;
}
// Where lane l's (x, y) pair lies in the unpacked rows (x0 y0 x2 y2 | x1 y1 x3 y3).
GRANULAR_AVX2_INLINE constexpr int pair_at(int l) {
  return (l & 1) * ContactBatch::kW + (l >> 1) * 2;
}
// The box for the lanes: its periodicity, and each axis's length, half length and negative
// half length splat once per slab.
struct LaneBox {
  bool px, py, pz;
  V len0, len1, len2, hl0, hl1, hl2, nhl0, nhl1, nhl2;
};
GRANULAR_AVX2_INLINE LaneBox lane_box(const PeriodicBox& b) {
  using CB = ContactBatch;
  const double lx = b.len[0], ly = b.len[1], lz = b.len[2];
  const V hl0 = CB::splat(0.5 * lx), hl1 = CB::splat(0.5 * ly), hl2 = CB::splat(0.5 * lz);
  return {b.periodic[0], b.periodic[1], b.periodic[2], CB::splat(lx), CB::splat(ly), CB::splat(lz),
          hl0,           hl1,           hl2,           -hl0,          -hl1,          -hl2};
}
// The separation x_i - x_j (minimum image) and the radii of the four entries (ii, jj), and
// which of the first `valid` lanes touch: split_row's test, touching() operation for
// operation (r2: the squared distance it compares).
// `Packed`: the positions and radii come from the packed records `pack` (ParticlePack)
// instead of x and rad.
template <bool Packed>
GRANULAR_AVX2_INLINE M touching_lanes(const LaneBox& lb, const double* x, const double* rad,
                                      const double* pack, const int* ii, const int* jj, int valid,
                                      V& X, V& Y, V& Z, V& ai, V& aj, V& r2) {
  V xi0, xi1, xi2, xj0, xj1, xj2;
  if constexpr (Packed) {
    load_packed(pack, ParticlePack::kPosRadius, ii, xi0, xi1, xi2, ai);
    load_packed(pack, ParticlePack::kPosRadius, jj, xj0, xj1, xj2, aj);
  } else {
    load3(x, ii, xi0, xi1, xi2), load3(x, jj, xj0, xj1, xj2);
    ai = load1(rad, ii), aj = load1(rad, jj);
  }
  X = lb.px ? min_image4(xi0 - xj0, lb.len0, lb.hl0, lb.nhl0) : xi0 - xj0;
  Y = lb.py ? min_image4(xi1 - xj1, lb.len1, lb.hl1, lb.nhl1) : xi1 - xj1;
  Z = lb.pz ? min_image4(xi2 - xj2, lb.len2, lb.hl2, lb.nhl2) : xi2 - xj2;
  const V sum = ai + aj;
  r2 = X * X + Y * Y + Z * Z;
  return (M)(r2 < sum * sum) & (M{0, 1, 2, 3} < valid);
}
}  // namespace near_stream_detail

// The stream entries e0 .. e1 - 1 (one slab) and the slab's rows without near entries
// (empty[z0 .. z1 - 1]) with the batched law L, its form and every pair's parameters pp: the
// forces, torques and springs of the batched rows, bitwise. `Packed`: the particles' inputs come
// from `pack` (ParticlePack, the values of the arrays of hv).
template <BatchLaw L, bool Packed>
GRANULAR_AVX2 void near_stream_slab(const HostParticleViews& hv, const PeriodicBox& b,
                                    const BatchParams& pp, const BatchForm& form, const int* si,
                                    const int* sj, const int* sr, int e0, int e1, const int* empty,
                                    int z0, int z1, double* hist, const HostVec3& fh,
                                    const HostVec3& qh, const double rate[3], double dt,
                                    const double* pack) {
  using namespace near_stream_detail;
  using CB = ContactBatch;
  constexpr int H = batch_history(L), O = batch_spring_at(L);  // the row, and its spring
  constexpr long S = ParticlePack::kStride;
  constexpr int kAhead = 16;     // entries
  for (int z = z0; z < z1; ++z)  // a row's empty sum: +0 (see the head of this file)
    for (int d = 0; d < 3; ++d) fh(empty[z], d) += 0.0, qh(empty[z], d) += 0.0;
  // Local copies of the views' pointers: held in registers, not reloaded after each store.
  double* const f = fh.p;
  double* const q = qh.p;
  const double* const x = &hv.x(0, 0);
  const double* const v = &hv.v(0, 0);
  const double* const w = &hv.w(0, 0);
  const double* const rad = &hv.radius(0);
  const double* const mass = &hv.mass(0);
  constexpr bool masses = L == BatchLaw::HertzRestitution;
  const LaneBox lb = lane_box(b);
  const V r30 = CB::splat(rate[0]), r31 = CB::splat(rate[1]), r32 = CB::splat(rate[2]);
  const V vdt = CB::splat(dt);
  const CB::LaneParams par = CB::splat(pp);
  // The owner whose row is being summed, and its sums: (x, y) pairs and z.
  int cur = -1;
  __m128d fxy = _mm_setzero_pd(), qxy = _mm_setzero_pd();
  double fz = 0.0, qz = 0.0;
  // The law's outputs (force on the owner, torques on owner and partner, spring) of the
  // four lanes: the (x, y) pair of lane l at xy[o] + pair_at(l), its z at z4[o][l].
  alignas(32) double xy[4][2 * CB::kW], z4[4][CB::kW];
  alignas(32) double dmax[CB::kW];  // the hysteretic law's delta_max of the four lanes
  for (int e = e0; e < e1; e += CB::kW) {
    const int valid = e1 - e < CB::kW ? e1 - e : CB::kW;
    // The partners of the entries 16 ahead (four vectors): their lines are requested now, so
    // that their misses overlap this vector's work instead of stalling its loads and its
    // scatter (1.02-1.04x against requesting the scatter's lines of this vector only).
    if (e + kAhead + CB::kW <= e1)
      for (int l = 0; l < CB::kW; ++l) {
        const int ja = sj[e + kAhead + l];
        if constexpr (Packed) {  // a record's 96 bytes span two lines
          const double* const r = pack + S * ja;
          __builtin_prefetch(r);
          __builtin_prefetch(r + ParticlePack::kSpin);
        } else {
          __builtin_prefetch(x + 3 * ja);
          __builtin_prefetch(v + 3 * ja);
          __builtin_prefetch(w + 3 * ja);
          if (masses) __builtin_prefetch(mass + ja);
        }
        __builtin_prefetch(f + 3 * ja, 1);
        __builtin_prefetch(q + 3 * ja, 1);
      }
    const int *const ii = si + e, *const jj = sj + e;
    CB::Lanes c;
    V r2;
    const M touch =
        touching_lanes<Packed>(lb, x, rad, pack, ii, jj, valid, c.X, c.Y, c.Z, c.ai, c.aj, r2);
    const int touching = CB::lanes(touch);
    if (touching) {
      V vi0, vi1, vi2, vj0, vj1, vj2;
      if constexpr (Packed) {  // the velocity's quarter ends with the mass
        load_packed(pack, ParticlePack::kVelocity, ii, vi0, vi1, vi2, c.mi);
        load_packed(pack, ParticlePack::kVelocity, jj, vj0, vj1, vj2, c.mj);
      } else {
        load3(v, ii, vi0, vi1, vi2), load3(v, jj, vj0, vj1, vj2);
        if constexpr (masses) c.mi = load1(mass, ii), c.mj = load1(mass, jj);
      }
      c.d0 = vi0 - vj0 + r30 * c.X;  // as set_motion
      c.d1 = vi1 - vj1 + r31 * c.Y;
      c.d2 = vi2 - vj2 + r32 * c.Z;
      if constexpr (Packed) {
        V pad;
        load_packed(pack, ParticlePack::kSpin, ii, c.wi0, c.wi1, c.wi2, pad);
        load_packed(pack, ParticlePack::kSpin, jj, c.wj0, c.wj1, c.wj2, pad);
      } else {
        load3(w, ii, c.wi0, c.wi1, c.wi2), load3(w, jj, c.wj0, c.wj1, c.wj2);
      }
      if constexpr (L == BatchLaw::Hysteretic)
        load4(hist, sr + e, c.D, c.s0, c.s1, c.s2);
      else
        load3(hist, sr + e, c.s0, c.s1, c.s2);
      CB::law<L>(c, par, vdt, form, touch);
      if constexpr (L == BatchLaw::Hysteretic) CB::store(dmax, c.D);
      // Unpacked into (x, y) pairs, so that the scatter below moves each lane's vectors as
      // one 16-byte pair and a z: a third fewer loads, stores and additions than component
      // by component (1.00-1.06x within one run), each component's operation unchanged.
      const V ox[4] = {c.F0, c.q0, c.p0, c.s0}, oy[4] = {c.F1, c.q1, c.p1, c.s1};
      const V oz[4] = {c.F2, c.q2, c.p2, c.s2};
      for (int o = 0; o < 4; ++o) {
        CB::store(xy[o], (V)_mm256_unpacklo_pd((__m256d)ox[o], (__m256d)oy[o]));
        CB::store(xy[o] + CB::kW, (V)_mm256_unpackhi_pd((__m256d)ox[o], (__m256d)oy[o]));
        CB::store(z4[o], oz[o]);
      }
    }
    for (int l = 0; l < valid; ++l) {
      const int i = si[e + l];
      if (i != cur) {  // the previous row ends: its owner's own sum
        if (cur >= 0) add3(f + 3L * cur, fxy, fz), add3(q + 3L * cur, qxy, qz);
        cur = i;
        fxy = qxy = _mm_setzero_pd();
        fz = qz = 0.0;
      }
      double* const h = hist + H * static_cast<long>(sr[e + l]);
      if (!(touching >> l & 1)) {
        forget_history<H>(h, 0);
        continue;
      }
      // The batched rows' flush, contact by contact: f_i += F, f_j -= F, q_i += q, q_j += p.
      const long j3 = 3L * sj[e + l];
      const int at = pair_at(l);
      const __m128d F = _mm_load_pd(xy[0] + at);
      fxy = _mm_add_pd(fxy, F), fz += z4[0][l];
      double* const fj = f + j3;
      _mm_storeu_pd(fj, _mm_sub_pd(_mm_loadu_pd(fj), F));
      fj[2] -= z4[0][l];
      qxy = _mm_add_pd(qxy, _mm_load_pd(xy[1] + at)), qz += z4[1][l];
      add3(q + j3, _mm_load_pd(xy[2] + at), z4[2][l]);
      if constexpr (O > 0) h[0] = dmax[l];
      _mm_storeu_pd(h + O, _mm_load_pd(xy[3] + at));
      h[O + 2] = z4[3][l];
    }
  }
  if (cur >= 0) add3(f + 3L * cur, fxy, fz), add3(q + 3L * cur, qxy, qz);
}

// The same for the frictionless linear law (pn for every pair): contact_frame and
// linear_normal_force of kernels/contact/lane_law.inc in the lanes (r, n, delta, the approach
// speed, fn = kn delta + gn delta_dot, f = fn n), each touching lane's force added to its owner's
// sum and taken from its partner's, in stream order: the forces of the rows (one_pass_row),
// bitwise. No spring, no torque; a row without near entries adds its +0 to the force only, as
// there.
GRANULAR_AVX2 inline void near_stream_slab_normal(const HostParticleViews& hv, const PeriodicBox& b,
                                                  const LinearNormal::Params& pn, const int* si,
                                                  const int* sj, int e0, int e1, const int* empty,
                                                  int z0, int z1, const HostVec3& fh,
                                                  const double rate[3]) {
  using namespace near_stream_detail;
  using CB = ContactBatch;
  constexpr int kAhead = 16;  // entries, as near_stream_slab
  for (int z = z0; z < z1; ++z)
    for (int d = 0; d < 3; ++d) fh(empty[z], d) += 0.0;
  double* const f = fh.p;
  const double* const x = &hv.x(0, 0);
  const double* const v = &hv.v(0, 0);
  const double* const rad = &hv.radius(0);
  const LaneBox lb = lane_box(b);
  const V r30 = CB::splat(rate[0]), r31 = CB::splat(rate[1]), r32 = CB::splat(rate[2]);
  const V kn = CB::splat(pn.kn), gn = CB::splat(pn.gn);
  int cur = -1;
  __m128d fxy = _mm_setzero_pd();
  double fz = 0.0;
  alignas(32) double xy[2 * CB::kW], z4[CB::kW];  // the forces, as near_stream_slab's xy[0]
  for (int e = e0; e < e1; e += CB::kW) {
    const int valid = e1 - e < CB::kW ? e1 - e : CB::kW;
    if (e + kAhead + CB::kW <= e1)
      for (int l = 0; l < CB::kW; ++l) {
        const int ja = sj[e + kAhead + l];
        __builtin_prefetch(x + 3 * ja);
        __builtin_prefetch(v + 3 * ja);
        __builtin_prefetch(f + 3 * ja, 1);
      }
    const int *const ii = si + e, *const jj = sj + e;
    V X, Y, Z, ai, aj, r2;
    const int touching =
        CB::lanes(touching_lanes<false>(lb, x, rad, nullptr, ii, jj, valid, X, Y, Z, ai, aj, r2));
    if (touching) {
      V vi0, vi1, vi2, vj0, vj1, vj2;
      load3(v, ii, vi0, vi1, vi2), load3(v, jj, vj0, vj1, vj2);
      const V r[3] = {X, Y, Z};
      const V dv[3] = {vi0 - vj0 + r30 * X, vi1 - vj1 + r31 * Y, vi2 - vj2 + r32 * Z};
      V n[3], delta, vn;
      contact_frame(r, r2, ai, aj, dv, n, delta, vn);
      const V fn = linear_normal_force(kn, gn, delta, -vn);
      const V F0 = fn * n[0], F1 = fn * n[1], F2 = fn * n[2];
      CB::store(xy, (V)_mm256_unpacklo_pd((__m256d)F0, (__m256d)F1));
      CB::store(xy + CB::kW, (V)_mm256_unpackhi_pd((__m256d)F0, (__m256d)F1));
      CB::store(z4, F2);
    }
    for (int l = 0; l < valid; ++l) {
      const int i = si[e + l];
      if (i != cur) {  // the previous row ends: its owner's own sum
        if (cur >= 0) add3(f + 3L * cur, fxy, fz);
        cur = i;
        fxy = _mm_setzero_pd();
        fz = 0.0;
      }
      if (!(touching >> l & 1)) continue;
      const __m128d F = _mm_load_pd(xy + pair_at(l));
      fxy = _mm_add_pd(fxy, F), fz += z4[l];
      double* const fj = f + 3L * sj[e + l];
      _mm_storeu_pd(fj, _mm_sub_pd(_mm_loadu_pd(fj), F));
      fj[2] -= z4[l];
    }
  }
  if (cur >= 0) add3(f + 3L * cur, fxy, fz);
}

#endif  // GRANULAR_CONTACT_BATCH

}  // namespace granular
