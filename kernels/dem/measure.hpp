// Micro-to-macro measurements of a DEM state: energies, static stress, pressure,
// coordination (with rattlers), volume fraction, largest overlap. Per-particle values
// are summed with deterministic_column_sums, so the numbers do not depend on threads.
#pragma once
#include <Kokkos_Core.hpp>
#include <array>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "kernels/dem/contact_forces.hpp"
#include "kernels/dem/deterministic_sum.hpp"
#include "kernels/dem/neighbor_list.hpp"

namespace granular {

struct Measurements {
  double ekin = 0;      // translational + rotational kinetic energy
  double ekin_rot = 0;  // its rotational part
  double chi = 0;       // contact-number fluctuation <(Z - Zbar)^2>/Zbar^2 over non-rattlers
  double contact_histogram[7] = {};  // fraction of particles with 0, 1, ..., 5, >= 6 contacts
  double fabric[6] = {};             // (1/V) sum_p V_p sum_c n n  (xx yy zz xy xz yz)
  double epot = 0;                   // elastic energy stored in contacts
  double stress[6] = {};  // xx yy zz xy xz yz; static (contact) part, positive in compression
  double stress_normal[6] = {};      // the same sum with normal contact forces only
  double stress_tangential[6] = {};  // ... and with tangential contact forces only
  double pressure = 0;               // tr(stress)/3
  double contacts = 0;               // number of contacts (pairs)
  double z = 0;                      // 2 contacts / N
  double z_corrected = 0;            // contacts per non-rattler, counted on non-rattlers only
  double rattlers = 0;               // particles with fewer contacts than the threshold
  double particles = 0;              // all particles
  double phi = 0;                    // volume fraction (overlaps ignored)
  double max_overlap = 0;            // largest delta / min(a_i, a_j)
  double volume = 0;
};

// The measured values of one particle: a row of kMeasureColumns numbers. Columns: ekin,
// epot, stress (6), contacts, non-rattler flag, contacts of non-rattlers, normal-force stress
// (6), tangential-force stress (6), rotational kinetic energy, squared contacts of
// non-rattlers, contact-number histogram (7), fabric (6).
constexpr int kMeasureColumns = 38;

template <class ExecSpace, class Model, class HistoryView>
struct ParticleMeasure {
  ParticleViews<ExecSpace> pv;
  typename Particles<ExecSpace>::vec_view v, w;
  typename Particles<ExecSpace>::scalar_view mass, inertia;
  typename NeighborList<ExecSpace>::int_view offsets, neighbors, owned_end, pair_begin;
  HistoryView history;  // owners' rows (NeighborList::pair_begin)
  PeriodicBox b;
  Model m;
  int thr;

  // Fills row[0 .. kMeasureColumns) for particle i; returns its largest overlap ratio.
  KOKKOS_INLINE_FUNCTION double operator()(const int i, double* row) const {
    constexpr int H = Model::history;
    double sn[6] = {0, 0, 0, 0, 0, 0}, st[6] = {0, 0, 0, 0, 0, 0}, fab[6] = {0, 0, 0, 0, 0, 0};
    double epot = 0.0, mo = 0.0;
    int c = 0;
    const double zero[3] = {0, 0, 0};
    for (int k = offsets(i); k < offsets(i + 1); ++k) {
      // Evaluated from the owner's side (lower identity), where the history lives;
      // stress and energy of a pair are the same seen from either side.
      const int j = neighbors(k);
      const bool own = k < owned_end(i);  // owned entries come first in each row
      const int a = own ? i : j, c2 = own ? j : i;
      int q = k;  // the owner's entry of the pair (the list is symmetric: j owns one for i)
      if (!own) {
        q = offsets(j);
        while (q + 1 < owned_end(j) && neighbors(q) != i) ++q;
      }
      const int slot = pair_begin(a) + (q - offsets(a));
      PairState s;
      if (!pair_state(pv, b, zero, Model::rotations, a, c2, s)) continue;
      double h[H > 0 ? H : 1];
      if constexpr (H > 0)
        for (int q = 0; q < H; ++q) h[q] = history(slot, q);
      PairForce e;
      m.elastic(s, h, e);
      // sigma = (1/V) sum_c l (x) f with branch vector l = r n; each pair is seen twice.
      const double r = s.ai + s.aj - s.delta;
      const double l[3] = {0.5 * r * s.n[0], 0.5 * r * s.n[1], 0.5 * r * s.n[2]};
      const double fnv[3] = {e.fn * s.n[0], e.fn * s.n[1], e.fn * s.n[2]};
      const int ia[6] = {0, 1, 2, 0, 0, 1}, ib[6] = {0, 1, 2, 1, 2, 2};
      for (int q = 0; q < 6; ++q) {
        sn[q] += l[ia[q]] * fnv[ib[q]];
        st[q] += l[ia[q]] * e.ft[ib[q]];
        fab[q] += s.n[ia[q]] * s.n[ib[q]];
      }
      epot += 0.5 * m.energy(s, h);
      ++c;
      const double amin = s.ai < s.aj ? s.ai : s.aj;
      mo = s.delta / amin > mo ? s.delta / amin : mo;
    }
    const double v2 = v(i, 0) * v(i, 0) + v(i, 1) * v(i, 1) + v(i, 2) * v(i, 2);
    const double w2 = w(i, 0) * w(i, 0) + w(i, 1) * w(i, 1) + w(i, 2) * w(i, 2);
    row[0] = 0.5 * mass(i) * v2 + 0.5 * inertia(i) * w2;
    row[23] = 0.5 * inertia(i) * w2;
    row[24] = c >= thr ? static_cast<double>(c) * c : 0.0;
    for (int q = 0; q < 7; ++q) row[25 + q] = (c < 6 ? c == q : q == 6) ? 1.0 : 0.0;
    const double ai = pv.radius(i);
    const double vp = 4.0 / 3.0 * M_PI * ai * ai * ai;
    for (int q = 0; q < 6; ++q) row[32 + q] = vp * fab[q];
    row[1] = epot;
    for (int q = 0; q < 6; ++q) {
      row[2 + q] = sn[q] + st[q];
      row[11 + q] = sn[q];
      row[17 + q] = st[q];
    }
    row[8] = c;
    row[9] = c >= thr ? 1.0 : 0.0;
    row[10] = c >= thr ? c : 0.0;
    return mo;
  }
};

template <class ExecSpace, class Model, class HistoryView>
Measurements measure(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                     const HistoryView& history, const PeriodicBox& box, const Model& model,
                     int rattler_threshold, double particle_volume) {
  constexpr int NC = kMeasureColumns;
  using mem = typename ExecSpace::memory_space;
  const ParticleMeasure<ExecSpace, Model, HistoryView> pm{ParticleViews<ExecSpace>(p),
                                                          p.v,
                                                          p.w,
                                                          p.mass,
                                                          p.inertia,
                                                          nl.offsets(),
                                                          nl.neighbors(),
                                                          nl.owned_end(),
                                                          nl.pair_begin(),
                                                          history,
                                                          box,
                                                          model,
                                                          rattler_threshold};
  double max_overlap = 0.0;
  std::array<double, NC> sums{};
  if constexpr (forces_by_slabs<ExecSpace>()) {
    // Host: each fixed block of particles sums its rows as it goes, in index order (the
    // same sums as a per-particle table would give), so no n x NC table is allocated.
    constexpr int block = kDeterministicBlock;
    const int nblocks = (p.n + block - 1) / block;
    Kokkos::View<double**, Kokkos::LayoutRight, mem> partial("measure::block_sums", nblocks, NC);
    const int n = p.n;
    Kokkos::parallel_reduce(
        "dem::measure::blocks", Kokkos::RangePolicy<ExecSpace>(0, nblocks),
        KOKKOS_LAMBDA(const int bl, double& mo) {
          double acc[NC] = {}, row[NC];
          const int end = (bl + 1) * block < n ? (bl + 1) * block : n;
          for (int i = bl * block; i < end; ++i) {
            const double o = pm(i, row);
            mo = o > mo ? o : mo;
            for (int c = 0; c < NC; ++c) acc[c] += row[c];
          }
          for (int c = 0; c < NC; ++c) partial(bl, c) = acc[c];
        },
        Kokkos::Max<double>(max_overlap));
    for (int bl = 0; bl < nblocks; ++bl)
      for (int c = 0; c < NC; ++c) sums[c] += partial(bl, c);
  } else {
    // Device: the per-particle table in chunks of whole blocks, each chunk's block sums added
    // in block order (the same bits as one table of all particles), so the table costs a
    // fixed 320 MB instead of 304 B per particle (docs/gpu_memory.md).
    constexpr int chunk = 4096 * kDeterministicBlock;
    Kokkos::View<double**, Kokkos::LayoutRight, mem> per("measure::per_particle",
                                                         p.n < chunk ? p.n : chunk, NC);
    for (int begin = 0; begin < p.n; begin += chunk) {
      const int len = p.n - begin < chunk ? p.n - begin : chunk;
      double chunk_max = 0.0;
      Kokkos::parallel_reduce(
          "dem::measure::per_particle", Kokkos::RangePolicy<ExecSpace>(0, len),
          KOKKOS_LAMBDA(const int k, double& mo) {
            double row[NC];
            const double o = pm(begin + k, row);
            mo = o > mo ? o : mo;
            for (int c = 0; c < NC; ++c) per(k, c) = row[c];
          },
          Kokkos::Max<double>(chunk_max));
      max_overlap = begin == 0 || chunk_max > max_overlap ? chunk_max : max_overlap;
      accumulate_deterministic_column_sums<NC, ExecSpace>(per, len, sums);
    }
  }
  Measurements out;
  out.volume = box.volume();
  out.ekin = sums[0];
  out.ekin_rot = sums[23];
  for (int q = 0; q < 7; ++q) out.contact_histogram[q] = p.n > 0 ? sums[25 + q] / p.n : 0.0;
  for (int q = 0; q < 6; ++q) out.fabric[q] = sums[32 + q] / box.volume();
  out.epot = sums[1];
  for (int q = 0; q < 6; ++q) {
    out.stress[q] = sums[2 + q] / out.volume;
    out.stress_normal[q] = sums[11 + q] / out.volume;
    out.stress_tangential[q] = sums[17 + q] / out.volume;
  }
  out.pressure = (out.stress[0] + out.stress[1] + out.stress[2]) / 3.0;
  out.contacts = sums[8] / 2.0;
  out.z = p.n > 0 ? sums[8] / p.n : 0.0;
  out.rattlers = p.n - sums[9];
  out.particles = p.n;
  out.z_corrected = sums[9] > 0 ? sums[10] / sums[9] : 0.0;
  if (out.z_corrected > 0) {
    const double mean_sq = sums[24] / sums[9];
    out.chi = (mean_sq - out.z_corrected * out.z_corrected) / (out.z_corrected * out.z_corrected);
  }
  out.phi = particle_volume / out.volume;
  out.max_overlap = max_overlap;
  return out;
}

// Whether a state has a load-bearing contact network. Jammed packings keep at most about
// 15 % rattlers even at the loosest configurations studied (frictional, phi = 0.65); a
// packing that is unjamming loses its network gradually, and while it does a few particles
// keep the threshold number of contacts for minutes. Half the particles below the threshold
// separates the two with a wide margin on both sides.
inline bool is_jammed(const Measurements& m) {
  return m.z_corrected > 0 && m.rattlers <= 0.5 * m.particles;
}

}  // namespace granular

namespace granular {

// Positions by particle identity (row id(i) = x(i)), a reference that survives reordering.
template <class ExecSpace>
typename Particles<ExecSpace>::vec_view positions_by_id(const Particles<ExecSpace>& p) {
  typename Particles<ExecSpace>::vec_view out("measure::positions_by_id", p.n);
  auto x = p.x;
  auto id = p.id;
  Kokkos::parallel_for(
      "dem::positions_by_id", Kokkos::RangePolicy<ExecSpace>(0, p.n), KOKKOS_LAMBDA(const int i) {
        for (int d = 0; d < 3; ++d) out(id(i), d) = x(i, d);
      });
  return out;
}

struct NonAffine {
  double eta = 0;        // (1/M) sum_c |Delta| / |eps l|  (contacts with eps l != 0)
  double eta_ratio = 0;  // sum_c |Delta| / sum_c |eps l|
  double contacts = 0;   // M
  // The normal part only, Delta . n against the affine normal displacement (eps l) . n:
  // sum_c |Delta . n| / sum_c |(eps l) . n|, and the signed mean that undoes the affine
  // normal displacement, -sum_c (Delta . n) sgn((eps l) . n) / sum_c |(eps l) . n| (the
  // fluctuation theory's 2 rho in an isotropic strain).
  double eta_normal_ratio = 0;
  double normal_relaxation = 0;
};

// Displacements by identity from positions x0 to x1 (both by identity, same box).
template <class ExecSpace>
typename Particles<ExecSpace>::vec_view displacement_by_id(
    const typename Particles<ExecSpace>::vec_view& x0,
    const typename Particles<ExecSpace>::vec_view& x1, const PeriodicBox& box) {
  typename Particles<ExecSpace>::vec_view out("measure::displacement", x0.extent(0));
  const PeriodicBox b = box;
  Kokkos::parallel_for(
      "dem::displacement_by_id", Kokkos::RangePolicy<ExecSpace>(0, x0.extent(0)),
      KOKKOS_LAMBDA(const int i) {
        for (int d = 0; d < 3; ++d) out(i, d) = b.min_image(x1(i, d) - x0(i, d), d);
      });
  return out;
}

// Non-affine displacement fluctuation of the contacts of the current state relative to a
// reference (positions x0 by identity in box0; the box deformed about its lower corner).
// An optional `drift` (displacement by identity that the state makes without strain in
// the same time) is subtracted from every particle's displacement first.
// Each particle's non-affine displacement is u_i = x_i - A(x0_i), A the affine map
// x -> lo + (x - lo) L/L0; for a contact Delta = u_i - u_j is the relative displacement
// minus its affine part eps l, with eps = L/L0 - 1 per axis and l the branch vector.
template <class ExecSpace>
NonAffine nonaffine_fluctuation(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                                const PeriodicBox& box, const PeriodicBox& box0,
                                const typename Particles<ExecSpace>::vec_view& x0,
                                const typename Particles<ExecSpace>::vec_view& drift = {}) {
  const bool has_drift = drift.extent(0) == static_cast<size_t>(p.n);
  using mem = typename ExecSpace::memory_space;
  Kokkos::View<double**, Kokkos::LayoutRight, mem> per("measure::nonaffine", p.n, 7);
  const ParticleViews<ExecSpace> pv(p);
  auto offsets = nl.offsets(), neighbors = nl.neighbors(), owned_end = nl.owned_end();
  const PeriodicBox b = box;
  const double s[3] = {box.len[0] / box0.len[0], box.len[1] / box0.len[1],
                       box.len[2] / box0.len[2]};
  Kokkos::parallel_for(
      "dem::measure::nonaffine", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i) {
        double sum_d = 0, sum_e = 0, sum_ratio = 0, m = 0, sum_dn = 0, sum_dn_signed = 0,
               sum_en = 0;
        const Body bi = load_body(pv, i, false);
        const int idi = pv.id(i);
        for (int k = offsets(i); k < owned_end(i); ++k) {  // each contact once, by its owner
          const int j = neighbors(k);
          const int idj = pv.id(j);
          double rx, ry, rz, r2;
          if (!touching(pv, b, bi, j, rx, ry, rz, r2)) continue;
          const double l[3] = {rx, ry, rz};
          const double inv_r = 1.0 / Kokkos::Experimental::sqrt(r2);
          double dd = 0, ee = 0, dn = 0, en = 0;
          for (int d = 0; d < 3; ++d) {
            const double di = has_drift ? drift(idi, d) : 0.0;
            const double dj = has_drift ? drift(idj, d) : 0.0;
            const double ui =
                b.min_image(pv.x(i, d) - b.lo[d] - (x0(idi, d) - b.lo[d]) * s[d] - di, d);
            const double uj =
                b.min_image(pv.x(j, d) - b.lo[d] - (x0(idj, d) - b.lo[d]) * s[d] - dj, d);
            const double el = (s[d] - 1.0) * l[d];
            dd += (ui - uj) * (ui - uj);
            ee += el * el;
            dn += (ui - uj) * l[d] * inv_r;
            en += el * l[d] * inv_r;
          }
          sum_dn += Kokkos::Experimental::fabs(dn), sum_en += Kokkos::Experimental::fabs(en);
          sum_dn_signed += en > 0 ? dn : (en < 0 ? -dn : 0.0);
          dd = Kokkos::Experimental::sqrt(dd), ee = Kokkos::Experimental::sqrt(ee);
          sum_d += dd, sum_e += ee, m += 1.0;
          if (ee > 0) sum_ratio += dd / ee;
        }
        per(i, 0) = sum_d, per(i, 1) = sum_e, per(i, 2) = sum_ratio, per(i, 3) = m;
        per(i, 4) = sum_dn, per(i, 5) = sum_dn_signed, per(i, 6) = sum_en;
      });
  const auto sums = deterministic_column_sums<7, ExecSpace>(per, p.n);
  NonAffine out;
  out.contacts = sums[3];
  out.eta = sums[3] > 0 ? sums[2] / sums[3] : 0.0;
  out.eta_ratio = sums[1] > 0 ? sums[0] / sums[1] : 0.0;
  out.eta_normal_ratio = sums[6] > 0 ? sums[4] / sums[6] : 0.0;
  out.normal_relaxation = sums[6] > 0 ? -sums[5] / sums[6] : 0.0;
  return out;
}

}  // namespace granular
