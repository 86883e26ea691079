// The neighbour build's candidate sweep in AVX, for host backends with the particles stored
// in cell order (DemSystem's sorting): slot s of the cell order then holds particle s, so the
// candidates of a run of cells are consecutive particles and four of them are tested at once.
//
// The test is CellVisitor::Candidates', operation for operation in every lane (minimum image
// by selecting between the outcomes of its branches, no contraction into FMA), so the lists
// are the same, entry for entry and in the same order. The partners are compacted into the
// row by a table of lane positions instead of a branch or a counted store per candidate: in
// a stencil of ~50 candidates and ~8 partners the scalar sweep was 12 % of a frictionless
// step at N = 32768 (36 rebuilds in 2000 steps).
#pragma once
#include <cstring>

#include "core/dem/box.hpp"
#include "kernels/cpu/host_simd.hpp"

namespace granular {

#if GRANULAR_HOST_AVX

struct ContiguousSweep {
  using V = double __attribute__((vector_size(32)));
  using M = long __attribute__((vector_size(32)));
  using I = int __attribute__((vector_size(16)));
  using F4 = float __attribute__((vector_size(16)));

  const double* x;       // positions, particle-major (x, y, z)
  const double* radius;  // radii
  const int* id;         // identities (ownership: the lower one owns a pair)
  int n;                 // particles
  PeriodicBox box;
  double skin;

  // One particle's partners so far: how many, how many of higher identity.
  struct Tally {
    int count = 0, owned = 0;
  };

  // Tests particle i against the candidates of its stencil (visit.runs(i, ...): runs of
  // consecutive particles, i itself among them) and stores its partners in `row`, keeping at
  // most `cap` of them: the row has room for cap + 4 entries, and the partners beyond cap
  // overwrite its last four (the build sweeps such a row again). Returns the partners and
  // those of higher identity.
  template <class Visitor>
  GRANULAR_AVX Tally operator()(const Visitor& visit, int i, int* row, int cap) const {
    Runs runs;
    visit.runs(i, runs);
    // Everything the loop reads in locals: the row's stores could alias this object's
    // fields as far as the compiler knows.
    const double* const xs = x;
    const double* const rs = radius;
    const int* const ids = id;
    const int end = n;
    const double xi = xs[3 * i], yi = xs[3 * i + 1], zi = xs[3 * i + 2], ai = rs[i], sk = skin;
    const V vxi = splat(xi), vyi = splat(yi), vzi = splat(zi), vai = splat(ai), vsk = splat(sk);
    const I vid = {ids[i], ids[i], ids[i], ids[i]};
    const PeriodicBox b = box;
    const Image ix(b, 0), iy(b, 1), iz(b, 2);
    Tally t;
    for (int r = 0; r < runs.n; ++r) {
      const int s1 = runs.s1[r];
      int s = runs.s0[r];
      for (; s < s1 && s + 4 <= end; s += 4) {
        const double* p = xs + 3 * s;
        const V X = {p[0], p[3], p[6], p[9]}, Y = {p[1], p[4], p[7], p[10]};
        const V Z = {p[2], p[5], p[8], p[11]};
        const V rx = ix(vxi - X), ry = iy(vyi - Y), rz = iz(vzi - Z);
        const V cut = vai + load(rs + s) + vsk;
        int m = mask(rx * rx + ry * ry + rz * rz < cut * cut);
        // Lanes past the run, and i's own lane, are no candidates.
        if (s1 - s < 4) m &= (1 << (s1 - s)) - 1;
        const unsigned self = static_cast<unsigned>(i - s);
        m &= ~(static_cast<int>(self < 4u) << (self & 3u));
        I idv;
        std::memcpy(&idv, ids + s, sizeof idv);
        const int higher = __builtin_ia32_movmskps((F4)(idv > vid));
        const I js = I{s, s, s, s} + lanes_of(m);
        std::memcpy(row + (t.count < cap ? t.count : cap), &js, sizeof js);
        t.count += popcount4(m);
        t.owned += popcount4(m & higher);
      }
      // The last few particles of the array: one at a time (no read past its end).
      for (; s < s1; ++s) {
        if (s == i) continue;
        const double rx = b.min_image(xi - xs[3 * s], 0);
        const double ry = b.min_image(yi - xs[3 * s + 1], 1);
        const double rz = b.min_image(zi - xs[3 * s + 2], 2);
        const double cut = ai + rs[s] + sk;
        const bool in = rx * rx + ry * ry + rz * rz < cut * cut;
        row[t.count < cap ? t.count : cap] = s;
        t.owned += in & (ids[s] > ids[i]);
        t.count += in;
      }
    }
    return t;
  }

 private:
  GRANULAR_AVX_INLINE static V splat(double a) { return V{a, a, a, a}; }
  GRANULAR_AVX_INLINE static V load(const double* a) {
    V v;
    std::memcpy(&v, a, sizeof v);
    return v;
  }
  GRANULAR_AVX_INLINE static int mask(M m) { return __builtin_ia32_movmskpd256((V)m); }
  // PeriodicBox::min_image along one axis in four lanes: both outcomes of its branches,
  // selected.
  struct Image {
    bool periodic;
    V l, half, minus_half;
    GRANULAR_AVX_INLINE Image(const PeriodicBox& b, int d)
        : periodic(b.periodic[d]),
          l(splat(b.len[d])),
          half(splat(0.5 * b.len[d])),
          minus_half(splat(-0.5 * b.len[d])) {}
    GRANULAR_AVX_INLINE V operator()(V dx) const {
      if (!periodic) return dx;
      return dx > half ? dx - l : (dx < minus_half ? dx + l : dx);
    }
  };
  // The runs of a stencil (at most 3 per row of cells, 9 rows).
  struct Runs {
    int s0[27], s1[27];
    int n = 0;
    void operator()(int a, int b) { s0[n] = a, s1[n] = b, ++n; }
  };
  // The lanes set in m, in order, packed to the front.
  static I lanes_of(int m) {
    static constexpr int kLanes[16][4] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0},
                                          {2, 0, 0, 0}, {0, 2, 0, 0}, {1, 2, 0, 0}, {0, 1, 2, 0},
                                          {3, 0, 0, 0}, {0, 3, 0, 0}, {1, 3, 0, 0}, {0, 1, 3, 0},
                                          {2, 3, 0, 0}, {0, 2, 3, 0}, {1, 2, 3, 0}, {0, 1, 2, 3}};
    I v;
    std::memcpy(&v, kLanes[m], sizeof v);
    return v;
  }
  static int popcount4(int m) {
    static constexpr int kCount[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
    return kCount[m];
  }
};

#endif  // GRANULAR_HOST_AVX

}  // namespace granular
