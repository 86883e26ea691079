// Contact and background-damping forces: one generic loop over the neighbour list,
// templated on the contact model (the model struct holds the physics of one pair) and on a
// hook through which multi-contact laws act (kernels/dem/multicontact.hpp; none by default).
#pragma once
#include <Kokkos_Core.hpp>
#include <stdexcept>
#include <type_traits>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/cpu/contact_batch.hpp"
#include "kernels/cpu/host_rows.hpp"
#include "kernels/cpu/near_stream.hpp"
#include "kernels/dem/fixed_point.hpp"
#include "kernels/dem/neighbor_list.hpp"

namespace granular {

struct Damping {
  double translational = 0.0;  // gamma_b: f = -gamma_b (v - v_affine)
  double rotational = 0.0;     // gamma_br: q = -gamma_br omega
};

// The two-pass kernel's byte per pair row: 1 where the contact touched this step, 0 where it
// was apart (and its row was left unwritten). Empty where rows are not flagged.
template <class ExecSpace>
using RowFlags = Kokkos::View<unsigned char*, typename ExecSpace::memory_space>;

// One particle's state in registers: loaded once for i, once per partner j.
struct Body {
  double x[3], v[3], w[3], a, m;
  int s;
};

template <class Views>
KOKKOS_FORCEINLINE_FUNCTION Body load_body(const Views& v, int i, bool rotations) {
  Body b;
  for (int d = 0; d < 3; ++d) {
    b.x[d] = v.x(i, d);
    b.v[d] = v.v(i, d);
    b.w[d] = rotations ? v.w(i, d) : 0.0;
  }
  b.a = v.radius(i);
  b.m = v.mass(i);  // a dead load, removed by the compiler, for laws that do not use it
  b.s = v.species(i);
  return b;
}

// Geometry and relative motion of the pair (bi, bj) if they touch (quick rejection on
// squared distance first). Velocities are stored relative to the affine flow of the
// deforming box, so the pair's affine relative velocity rate * r_ij is added here.
template <class Views>
KOKKOS_FORCEINLINE_FUNCTION bool touching(const Views& v, const PeriodicBox& b, const Body& bi,
                                          int j, double& rx, double& ry, double& rz, double& r2) {
  rx = b.min_image(bi.x[0] - v.x(j, 0), 0);
  ry = b.min_image(bi.x[1] - v.x(j, 1), 1);
  rz = b.min_image(bi.x[2] - v.x(j, 2), 2);
  const double sum = bi.a + v.radius(j);
  r2 = rx * rx + ry * ry + rz * rz;
  return r2 < sum * sum;
}

KOKKOS_FORCEINLINE_FUNCTION void pair_geometry(const Body& bi, const Body& bj, double rx, double ry,
                                               double rz, double r2, const double rate[3],
                                               bool rotations, PairState& s) {
  s.ai = bi.a, s.aj = bj.a;
  const double r[3] = {rx, ry, rz};
  const double dv[3] = {bi.v[0] - bj.v[0] + rate[0] * rx, bi.v[1] - bj.v[1] + rate[1] * ry,
                        bi.v[2] - bj.v[2] + rate[2] * rz};
  double vn;
  contact_frame(r, r2, s.ai, s.aj, dv, s.n, s.delta, vn);
  s.si = bi.s, s.sj = bj.s;
  s.mstar = reduced_pair(bi.m, bj.m);
  s.wall = false;
  s.delta_dot = -vn;
  if (rotations) {
    // Contact point in the middle of the overlap, at lever arms a - delta/2 from both
    // centres: then the torques of a tangential force balance exactly and angular
    // momentum is conserved. Contact-point velocity v_i - l_i w_i x n minus v_j + l_j w_j x n.
    double li, lj;
    contact_slip(dv, s.n, vn, s.delta, s.ai, s.aj, bi.w, bj.w, li, lj, s.vt);
    for (int d = 0; d < 3; ++d) s.wrel[d] = bi.w[d] - bj.w[d];
  } else {
    for (int d = 0; d < 3; ++d) s.vt[d] = dv[d] - vn * s.n[d], s.wrel[d] = 0.0;
  }
}

// Convenience for code off the hot path: the full state of pair (i, j), false if apart.
template <class Views>
KOKKOS_INLINE_FUNCTION bool pair_state(const Views& v, const PeriodicBox& b, const double rate[3],
                                       bool rotations, int i, int j, PairState& s) {
  const Body bi = load_body(v, i, rotations);
  double rx, ry, rz, r2;
  if (!touching(v, b, bi, j, rx, ry, rz, r2)) return false;
  pair_geometry(bi, load_body(v, j, rotations), rx, ry, rz, r2, rate, rotations, s);
  return true;
}

template <class ExecSpace>
struct ParticleViews {
  using mem = typename ExecSpace::memory_space;
  Kokkos::View<double*[3], mem> x, v, w;
  Kokkos::View<double*, mem> radius, mass;
  Kokkos::View<int*, mem> species, id;
  explicit ParticleViews(const Particles<ExecSpace>& p)
      : x(p.x), v(p.v), w(p.w), radius(p.radius), mass(p.mass), species(p.species), id(p.id) {}
};

// The mixed-precision force pass's view of the particles (DemParams::mixed_precision,
// kernels/dem/fixed_point.hpp): positions read as fixed-point integers, everything else as in
// ParticleViews. Its load_body and touching below are picked over the generic ones by overload
// resolution, so the kernels that take their views as a template parameter are written once.
template <class ExecSpace>
struct FixedPointViews : ParticleViews<ExecSpace> {
  typename FixedPositions<ExecSpace>::view q;
  double step[3];
  FixedPointViews(const Particles<ExecSpace>& p, const FixedPositions<ExecSpace>& fixed)
      : ParticleViews<ExecSpace>(p), q(fixed.q) {
    for (int d = 0; d < 3; ++d) step[d] = fixed.step[d];
  }
};

// A body whose position is its integers (x is left unset: the pair's geometry uses only the
// separation).
struct FixedBody : Body {
  std::uint32_t q[3];
};

template <class ExecSpace>
KOKKOS_FORCEINLINE_FUNCTION FixedBody load_body(const FixedPointViews<ExecSpace>& v, int i,
                                                bool rotations) {
  FixedBody b;
  for (int d = 0; d < 3; ++d) {
    b.x[d] = 0.0;
    b.q[d] = v.q(i, d);
    b.v[d] = v.v(i, d);
    b.w[d] = rotations ? v.w(i, d) : 0.0;
  }
  b.a = v.radius(i);
  b.m = v.mass(i);
  b.s = v.species(i);
  return b;
}

// touching() with the separation from the integers: the wrap-around is the minimum image (a
// walled dimension's listed pairs are never half a box apart, DemSystem checks the lengths).
template <class ExecSpace>
KOKKOS_FORCEINLINE_FUNCTION bool touching(const FixedPointViews<ExecSpace>& v, const PeriodicBox&,
                                          const FixedBody& bi, int j, double& rx, double& ry,
                                          double& rz, double& r2) {
  rx = fixed_point_separation(bi.q[0], v.q(j, 0), v.step[0]);
  ry = fixed_point_separation(bi.q[1], v.q(j, 1), v.step[1]);
  rz = fixed_point_separation(bi.q[2], v.q(j, 2), v.step[2]);
  const double sum = bi.a + v.radius(j);
  r2 = rx * rx + ry * ry + rz * rz;
  return r2 < sum * sum;
}

// Extension point of the pair pass for laws that need more than the pair (multi-contact,
// kernels/dem/multicontact.hpp): a hook may replace the model's evaluation of a touching contact
// and record per-contact data. The classical pass uses NoPairHook, and `if constexpr` then
// compiles exactly the classical kernel (same arithmetic, same results bit for bit).
struct NoPairHook {
  static constexpr bool active = false;
  static constexpr bool batchable = false;  // see compute_pair_forces_batched
  static constexpr bool corrected = false;
  static constexpr const char* label = "dem::compute_forces::pairs";
  template <class Model>
  KOKKOS_INLINE_FUNCTION void evaluate(const Model&, int, const PairState&, double, double*,
                                       PairForce&) const {}
  KOKKOS_INLINE_FUNCTION void apart(int) const {}
};

// Gather pass: every particle sums its contacts in list order, the owned ones from its own
// consecutive rows (from own_row(i) on), the others from the partner's row other_row(k) with
// the force's sign flipped. No atomics, and a summation order independent of threads and
// backend. The classical laws' rows are pair rows (pair_begin, pair_row); the multi-contact
// laws' are list entries (offsets, mirror).
// `flags` (pair rows only; empty: every row is read): one byte per row, 0 where the
// contacts pass found the pair apart and left its row unwritten. Such a row is not read; the
// sums add the +0 its zero row would have added (x + 0 is not x when x is -0), so the bits
// are those of zero rows.
template <class ExecSpace, class Model, class PairView, class IndexView>
void gather_contact_forces(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                           const PairView& pair, const Damping& damping, const IndexView& own_row,
                           const IndexView& other_row, const char* label,
                           const RowFlags<ExecSpace>& flags = {}) {
  const ParticleViews<ExecSpace> pv(p);
  auto f = p.f, torque = p.torque;
  auto offsets = nl.offsets(), owned_end = nl.owned_end();
  const double gb = damping.translational, gr = damping.rotational;
  const bool flagged = flags.extent(0) > 0;
  Kokkos::parallel_for(
      label, Kokkos::RangePolicy<ExecSpace>(0, p.n), KOKKOS_LAMBDA(const int i) {
        constexpr bool rot = Model::rotations;
        (void)torque.extent(0);  // nvcc: capture outside the constexpr-ifs that use them
        (void)gr;
        double fi[3] = {-gb * pv.v(i, 0), -gb * pv.v(i, 1), -gb * pv.v(i, 2)};
        double qi[3] = {0, 0, 0};
        if constexpr (rot)
          for (int d = 0; d < 3; ++d) qi[d] = -gr * pv.w(i, d);
        const int r0 = own_row(i), own = owned_end(i) - offsets(i);
        for (int r = r0; r < r0 + own; ++r) {
          if (flagged && flags(r) == 0) {
            for (int d = 0; d < 3; ++d) fi[d] += 0.0;
            if constexpr (rot)
              for (int d = 0; d < 3; ++d) qi[d] += 0.0;
            continue;
          }
          for (int d = 0; d < 3; ++d) fi[d] += pair(r, d);
          if constexpr (rot)
            for (int d = 0; d < 3; ++d) qi[d] += pair(r, 3 + d);
        }
        for (int k = owned_end(i); k < offsets(i + 1); ++k) {
          const int r = other_row(k);
          if (flagged && flags(r) == 0) {  // fi - (+0) is fi, -0 included
            if constexpr (rot)
              for (int d = 0; d < 3; ++d) qi[d] += 0.0;
            continue;
          }
          for (int d = 0; d < 3; ++d) fi[d] -= pair(r, d);
          if constexpr (rot)
            for (int d = 0; d < 3; ++d) qi[d] += pair(r, 6 + d);
        }
        for (int d = 0; d < 3; ++d) f(i, d) = fi[d];
        if constexpr (rot)
          for (int d = 0; d < 3; ++d) torque(i, d) = qi[d];
      });
}

// Two passes indexed by list entry, for the multi-contact laws (kernels/dem/multicontact.hpp),
// whose per-entry data both sides of a contact read; the classical laws use the pair rows
// below. Pairs: the owner of each contact (the particle with the lower identity, which
// survives reordering) evaluates it once,
// advances its history and stores the force on i and the torques on i and j. Gather: every
// particle sums the contacts of its list in list order (owner entries directly, the others
// through the mirror entry, with the sign of the force flipped). No atomics, half the pair
// work of a full list, and a summation order that does not depend on threads or backend.
// `pair` must have num_entries rows and 3 (9 with rotations) columns.
// The passes are separate functions so that multi-contact laws can act between them.
template <class ExecSpace, class Model, class HistoryView, class PairView, class Hook = NoPairHook>
void compute_pair_forces(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                         const HistoryView& history, const PairView& pair, const PeriodicBox& box,
                         const Model& model, const double strain_rate[3], double dt,
                         const Hook& pair_hook = Hook()) {
  const ParticleViews<ExecSpace> pv(p);
  auto offsets = nl.offsets(), neighbors = nl.neighbors();
  auto owned_end = nl.owned_end(), pair_begin = nl.pair_begin();
  const PeriodicBox b = box;
  const Model m = model;
  const Hook hook = pair_hook;
  const double rate[3] = {strain_rate[0], strain_rate[1], strain_rate[2]};
  // Compile-time switches are re-declared inside each kernel: nvcc would otherwise
  // capture them, which extended lambdas cannot do in an if-constexpr condition.
  Kokkos::parallel_for(
      Hook::label, Kokkos::RangePolicy<ExecSpace>(0, p.n), KOKKOS_LAMBDA(const int i) {
        constexpr int H = Model::history;
        constexpr bool rot = Model::rotations;
        constexpr int NB = rot ? 9 : 3;
        (void)history.extent(0);  // nvcc: capture outside the constexpr-ifs that use them
        (void)pair_begin.extent(0);
        (void)hook;
        (void)m;
        (void)dt;
        const double r3[3] = {rate[0], rate[1], rate[2]};
        const Body bi = load_body(pv, i, rot);
        const int row0 = H > 0 ? pair_begin(i) - offsets(i) : 0;  // history row of entry k
        for (int k = offsets(i); k < owned_end(i); ++k) {         // the contacts i owns
          const int j = neighbors(k);
          double rx, ry, rz, r2;
          if (!touching(pv, b, bi, j, rx, ry, rz, r2)) {
            // Not touching: no force, and the contact's history is forgotten. Most such
            // slots are already zero; reading is cheaper than rewriting them every step.
            for (int c = 0; c < NB; ++c) pair(k, c) = 0.0;
            if constexpr (H > 0) {
              bool stale = false;
              for (int c = 0; c < H; ++c) stale = stale || history(row0 + k, c) != 0.0;
              if (stale)
                for (int c = 0; c < H; ++c) history(row0 + k, c) = 0.0;
            }
            if constexpr (Hook::active) hook.apart(k);
            continue;
          }
          PairState s;
          pair_geometry(bi, load_body(pv, j, rot), rx, ry, rz, r2, r3, rot, s);
          double h[H > 0 ? H : 1];
          if constexpr (H > 0)
            for (int c = 0; c < H; ++c) h[c] = history(row0 + k, c);
          PairForce out;
          if constexpr (Hook::active)
            hook.evaluate(m, k, s, dt, h, out);
          else
            m.evaluate(s, dt, h, out);
          if constexpr (H > 0)
            for (int c = 0; c < H; ++c) history(row0 + k, c) = h[c];
          for (int d = 0; d < 3; ++d) pair(k, d) = out.f[d];
          if constexpr (rot)
            for (int d = 0; d < 3; ++d) pair(k, 3 + d) = out.q[d], pair(k, 6 + d) = out.qj[d];
        }
      });
}

template <class ExecSpace, class Model, class PairView>
void gather_pair_forces(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                        const PairView& pair, const Damping& damping) {
  gather_contact_forces<ExecSpace, Model>(p, nl, pair, damping, nl.offsets(), nl.mirror(),
                                          "dem::compute_forces::gather");
}

// The classical laws' two passes, indexed by pair rows (NeighborList::pair_begin): the
// per-contact array has one row per contact, half the list, next to the history rows.
// One contact: evaluated into row r (force on the owner i, torques on i and on the partner j),
// its history advanced; an apart contact forgets its history and leaves a zero row, or, where
// rows are flagged (`flagged`), marks its byte of `flags` 0 and leaves its row unwritten:
// about 40 % of the listed pairs of a dense packing are apart, and their zero rows were
// written by this pass and read back by the gather.
template <class Model, class PV, class B, class HistoryView, class PairView, class FlagView>
KOKKOS_INLINE_FUNCTION void contact_row(const PV& pv, const PeriodicBox& b, const Model& m,
                                        const B& bi, const int j, const int r,
                                        const HistoryView& history, const PairView& pair,
                                        const FlagView& flags, const bool flagged,
                                        const double r3[3], const double dt) {
  constexpr int H = Model::history;
  constexpr bool rot = Model::rotations;
  constexpr int NB = rot ? 9 : 3;
  (void)history;
  double rx, ry, rz, r2;
  if (!touching(pv, b, bi, j, rx, ry, rz, r2)) {
    if (flagged)
      flags(r) = 0;
    else
      for (int c = 0; c < NB; ++c) pair(r, c) = 0.0;
    if constexpr (H > 0) {  // most such rows are already zero: reading is cheaper
      bool stale = false;
      for (int c = 0; c < H; ++c) stale = stale || history(r, c) != 0.0;
      if (stale)
        for (int c = 0; c < H; ++c) history(r, c) = 0.0;
    }
    return;
  }
  if (flagged) flags(r) = 1;
  PairState s;
  pair_geometry(bi, load_body(pv, j, rot), rx, ry, rz, r2, r3, rot, s);
  double h[H > 0 ? H : 1];
  if constexpr (H > 0)
    for (int c = 0; c < H; ++c) h[c] = history(r, c);
  PairForce out;
  m.evaluate(s, dt, h, out);
  if constexpr (H > 0)
    for (int c = 0; c < H; ++c) history(r, c) = h[c];
  for (int d = 0; d < 3; ++d) pair(r, d) = out.f[d];
  if constexpr (rot)
    for (int d = 0; d < 3; ++d) pair(r, 3 + d) = out.q[d], pair(r, 6 + d) = out.qj[d];
}

// Contacts pass. One thread per contact (default): on a device the threads of a warp then
// all do the same work, where one thread per particle leaves most of a warp idle behind the
// particle with the most owned contacts, and consecutive threads touch consecutive rows.
// `thread_per_particle`: the earlier mapping (each owner loops over its contacts), kept to
// measure the difference; both evaluate every contact with the same arithmetic, so the
// results are the same bit for bit.
// `views`: ParticleViews, or FixedPointViews for the mixed-precision pass.
template <class ExecSpace, class Model, class PV, class HistoryView, class PairView>
void contact_rows_with(const PV& views, const Particles<ExecSpace>& p,
                       const NeighborList<ExecSpace>& nl, const HistoryView& history,
                       const PairView& pair, const PeriodicBox& box, const Model& model,
                       const double strain_rate[3], double dt, bool thread_per_particle,
                       const RowFlags<ExecSpace>& flags) {
  const PV pv = views;
  auto offsets = nl.offsets(), neighbors = nl.neighbors();
  auto owned_end = nl.owned_end(), pair_begin = nl.pair_begin(), pair_owner = nl.pair_owner();
  const PeriodicBox b = box;
  const Model m = model;
  const double rate[3] = {strain_rate[0], strain_rate[1], strain_rate[2]};
  const bool flagged = flags.extent(0) > 0;
  if (thread_per_particle) {
    Kokkos::parallel_for(
        "dem::compute_forces::contacts_by_particle", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i) {
          const double r3[3] = {rate[0], rate[1], rate[2]};
          const auto bi = load_body(pv, i, Model::rotations);
          const int row0 = pair_begin(i) - offsets(i);
          for (int k = offsets(i); k < owned_end(i); ++k)
            contact_row(pv, b, m, bi, neighbors(k), row0 + k, history, pair, flags, flagged, r3,
                        dt);
        });
    return;
  }
  Kokkos::parallel_for(
      "dem::compute_forces::contacts", Kokkos::RangePolicy<ExecSpace>(0, nl.num_pairs()),
      KOKKOS_LAMBDA(const int r) {
        const double r3[3] = {rate[0], rate[1], rate[2]};
        const int i = pair_owner(r);
        const int k = offsets(i) + r - pair_begin(i);  // the owner's list entry
        contact_row(pv, b, m, load_body(pv, i, Model::rotations), neighbors(k), r, history, pair,
                    flags, flagged, r3, dt);
      });
}

// `fixed` (mixed precision): the positions as fixed-point integers, refreshed for this pass.
template <class ExecSpace, class Model, class HistoryView, class PairView>
void compute_contact_rows(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                          const HistoryView& history, const PairView& pair, const PeriodicBox& box,
                          const Model& model, const double strain_rate[3], double dt,
                          bool thread_per_particle, const RowFlags<ExecSpace>& flags = {},
                          const FixedPositions<ExecSpace>* fixed = nullptr) {
  if (fixed)
    contact_rows_with(FixedPointViews<ExecSpace>(p, *fixed), p, nl, history, pair, box, model,
                      strain_rate, dt, thread_per_particle, flags);
  else
    contact_rows_with(ParticleViews<ExecSpace>(p), p, nl, history, pair, box, model, strain_rate,
                      dt, thread_per_particle, flags);
}

// A stretch of an owner row for the host kernel, split into its touching entries (list
// order, with the separation found by the distance test) and its apart ones. In a dense
// packing whether a listed pair touches is close to a coin toss, so a branch per entry was
// mispredicted about every other time; the split stores every entry and advances a count
// instead, and the apart entries' histories are forgotten after it. The touching entries go
// to the arrays of `SplitOut` (list entry k, partner j, separation, squared distance unless
// R2 is false): a RowSplit's for the contact-by-contact rows, the batch's own slots for the
// batched ones (which form |r|^2 again in their lanes: one store fewer per listed pair).
struct SplitOut {
  static constexpr int kMax = 64;  // entries per split at most
  int *k, *j;
  double *rx, *ry, *rz, *r2;
};
struct RowSplit {
  static constexpr int kChunk = 32;  // entries per stretch
  int k[kChunk], j[kChunk];
  double rx[kChunk], ry[kChunk], rz[kChunk], r2[kChunk];
  KOKKOS_FORCEINLINE_FUNCTION SplitOut out() { return {k, j, rx, ry, rz, r2}; }
};

// PeriodicBox::min_image with the box's length and periodicity given (held in registers).
KOKKOS_FORCEINLINE_FUNCTION double min_image_of(double dx, double l, bool periodic) {
  if (!periodic) return dx;
  if (dx > 0.5 * l)
    dx -= l;
  else if (dx < -0.5 * l)
    dx += l;
  return dx;
}

// The entries a row split reads. ListEntries: the row's own entries e = k, recording those
// within the near skin into `near` (i's near row; the next slot is `kept`: a slot never
// beyond the entry being read, so every store stays inside i's row).
struct ListEntries {
  int* near;
  double skin;
  static constexpr bool record = true;
  KOKKOS_FORCEINLINE_FUNCTION int k(int e) const { return e; }
};
// NearEntries: the near entries e of i's near row, read from the near list.
struct NearEntries {
  const int* near;
  static constexpr bool record = false;
  KOKKOS_FORCEINLINE_FUNCTION int k(int e) const { return near[e]; }
};

// Splits entries e0 .. e1 - 1 (at most SplitOut::kMax) of `src` and returns how many touch.
template <int H, bool Rot, bool R2 = true, class Src = ListEntries>
KOKKOS_FORCEINLINE_FUNCTION int split_row(const HostParticleViews& hv, const PeriodicBox& b,
                                          const Body& bi, const HostListRows& list, double* hist,
                                          const HostVec3& fh, const HostVec3& qh, int row0, int e0,
                                          int e1, const SplitOut& t, const Src& src, int& kept) {
  int far[SplitOut::kMax];
  int n = 0, apart = 0;
  // The box and the owner in locals: the stores to the split's arrays could alias the
  // box's fields as far as the compiler knows, which made it reload them for every entry.
  // The test is touching()'s, operation for operation (same bits).
  const double xi = bi.x[0], yi = bi.x[1], zi = bi.x[2], ai = bi.a;
  const double lx = b.len[0], ly = b.len[1], lz = b.len[2];
  const bool px = b.periodic[0], py = b.periodic[1], pz = b.periodic[2];
  double near_reach = 0.0;
  if constexpr (Src::record) near_reach = ai + src.skin;
  for (int e = e0; e < e1; ++e) {
    const int k = src.k(e);
    const int j = list.neighbors(k);
#if !defined(__CUDA_ARCH__)
    // The touching partners' velocities (and spins) are read and their forces (and torques)
    // written right after the split: their cache lines are requested now, while the distance
    // tests run, so that a large packing's misses overlap instead of following each other.
    __builtin_prefetch(&hv.v(j, 0));
    __builtin_prefetch(&fh(j, 0), 1);
    if (Rot) {
      __builtin_prefetch(&hv.w(j, 0));
      __builtin_prefetch(&qh(j, 0), 1);
    }
#endif
    const double rx = min_image_of(xi - hv.x(j, 0), lx, px);
    const double ry = min_image_of(yi - hv.x(j, 1), ly, py);
    const double rz = min_image_of(zi - hv.x(j, 2), lz, pz);
    const double aj = hv.radius(j);
    const double sum = ai + aj;
    const double r2 = rx * rx + ry * ry + rz * rz;
    const bool in = r2 < sum * sum;
    t.k[n] = k, t.j[n] = j;
    t.rx[n] = rx, t.ry[n] = ry, t.rz[n] = rz;
    if (R2) t.r2[n] = r2;
    far[apart] = k;
    n += in;
    apart += !in;
    if constexpr (Src::record) {
      const double reach = near_reach + aj;
      src.near[kept] = k;
      kept += r2 < reach * reach;
    }
  }
  for (int a = 0; a < apart; ++a) forget_history<H>(hist, row0 + far[a]);
  return n;
}

// The entries of owner row i to read: the list's (recording the near ones, Record) or the
// near list's (Use).
enum class NearMode { Record, Use };
struct RowEntries {
  int e0, e1;  // entries e0 .. e1 - 1 of the source
  int row0;    // history row of list entry k: row0 + k
};
template <NearMode Mode>
KOKKOS_FORCEINLINE_FUNCTION RowEntries row_entries(const HostListRows& list, const NearRows& nr,
                                                   int i) {
  const int kbeg = list.offsets(i), pb = list.pair_begin(i);
  if (Mode == NearMode::Use) return {pb, pb + nr.count[i], pb - kbeg};
  return {kbeg, list.owned_end(i), pb - kbeg};
}

// One owner row of the one-pass kernel below: particle i evaluates the contacts it owns,
// adds their forces to itself and scatters the reactions to its partners.
// `hist` holds the owners' rows (NeighborList::pair_begin).
template <class Model, NearMode Mode>
KOKKOS_FORCEINLINE_FUNCTION void one_pass_row(const HostParticleViews& hv, const PeriodicBox& b,
                                              const Model& m, const HostListRows& list,
                                              double* hist, const HostVec3& fh, const HostVec3& qh,
                                              const double r3[3], double dt, const NearRows& nr,
                                              int i) {
  constexpr int H = Model::history;
  constexpr bool rot = Model::rotations;
  const Body bi = load_body(hv, i, rot);
  double fi[3] = {0, 0, 0}, qi[3] = {0, 0, 0};
  const RowEntries re = row_entries<Mode>(list, nr, i);
  const int row0 = H > 0 ? re.row0 : 0;  // history row of entry k
  int kept = 0;
  for (int e0 = re.e0; e0 < re.e1; e0 += RowSplit::kChunk) {
    RowSplit t;
    const int e1 = e0 + RowSplit::kChunk < re.e1 ? e0 + RowSplit::kChunk : re.e1;
    int touching;
    if constexpr (Mode == NearMode::Use)
      touching = split_row<H, rot>(hv, b, bi, list, hist, fh, qh, row0, e0, e1, t.out(),
                                   NearEntries{nr.k}, kept);
    else
      touching = split_row<H, rot>(hv, b, bi, list, hist, fh, qh, row0, e0, e1, t.out(),
                                   ListEntries{nr.k + list.pair_begin(i), nr.skin}, kept);
    for (int c = 0; c < touching; ++c) {
      const int k = t.k[c], j = t.j[c];
      PairState s;
      pair_geometry(bi, load_body(hv, j, rot), t.rx[c], t.ry[c], t.rz[c], t.r2[c], r3, rot, s);
      double h[H > 0 ? H : 1];
      if (H > 0)
        for (int q = 0; q < H; ++q) h[q] = hist[(row0 + k) * H + q];
      PairForce out;
      m.evaluate(s, dt, h, out);
      if (H > 0)
        for (int q = 0; q < H; ++q) hist[(row0 + k) * H + q] = h[q];
      for (int d = 0; d < 3; ++d) {
        fi[d] += out.f[d];
        fh(j, d) -= out.f[d];
      }
      if (rot)
        for (int d = 0; d < 3; ++d) {
          qi[d] += out.q[d];
          qh(j, d) += out.qj[d];
        }
    }
  }
  if (Mode == NearMode::Record) nr.count[i] = kept;
  for (int d = 0; d < 3; ++d) fh(i, d) += fi[d];
  if (rot)
    for (int d = 0; d < 3; ++d) qh(i, d) += qi[d];
}

#if GRANULAR_CONTACT_BATCH
// The same rows with the contacts evaluated in batches (kernels/cpu/contact_batch.hpp): gather
// the touching contacts of whole rows, evaluate them four at a time (AVX), scatter row by
// row in list order. Bitwise the results of one_pass_row.
template <class Model, NearMode Mode>
void one_pass_rows_batched(const HostParticleViews& hv, const PeriodicBox& b, const Model& m,
                           const HostListRows& list, const HostArray<const int>& order,
                           double* hist, const HostVec3& fh, const HostVec3& qh,
                           const double rate[3], double dt, const NearRows& nr, int q_begin,
                           int q_end) {
  constexpr int H = Model::history;
  constexpr bool rot = Model::rotations;
  using Law = ContactBatchLaw<Model>;
  constexpr BatchLaw L = Law::law;
  static_assert(H == batch_history(L) && rot, "the batched law has a tangential spring");
  static_assert(ContactBatch::kCap <= SplitOut::kMax, "a batch-sized row must fit one split");
  const double r3[3] = {rate[0], rate[1], rate[2]};  // a local copy: no reloads after stores
  ContactBatch cb;
  if (Law::uniform(m)) cb.set_uniform(Law::pair(m, 0, 0));
  cb.form = Law::form(m);
  auto flush = [&] {
    cb.evaluate<L>(dt);
    int c = 0;
    for (int row = 0; row < cb.rows; ++row) {
      const int i = cb.row_i[row];
      double fi[3] = {0, 0, 0}, qi[3] = {0, 0, 0};
      for (; c < cb.row_end[row]; ++c) {
        const int j = cb.j[c];
        const double f[3] = {cb.f0[c], cb.f1[c], cb.f2[c]};
        for (int d = 0; d < 3; ++d) {
          fi[d] += f[d];
          fh(j, d) -= f[d];
        }
        const double qa[3] = {cb.q0[c], cb.q1[c], cb.q2[c]};
        const double qb[3] = {cb.p0[c], cb.p1[c], cb.p2[c]};
        for (int d = 0; d < 3; ++d) {
          qi[d] += qa[d];
          qh(j, d) += qb[d];
        }
        cb.store_history<L>(c, hist + cb.k[c] * H);  // the contact's history row
      }
      for (int d = 0; d < 3; ++d) fh(i, d) += fi[d];
      for (int d = 0; d < 3; ++d) qh(i, d) += qi[d];
    }
    cb.n = cb.rows = 0;
  };
  for (int q = q_begin; q < q_end; ++q) {
    const int i = order(q);
    const RowEntries re = row_entries<Mode>(list, nr, i);
    const int len = re.e1 - re.e0;
    if (cb.rows == ContactBatch::kCap || cb.n + len > ContactBatch::kCap) flush();
    if (len > ContactBatch::kCap) {  // a crowded row: evaluated on its own
      one_pass_row<Model, Mode>(hv, b, m, list, hist, fh, qh, r3, dt, nr, i);
      continue;
    }
    const Body bi = load_body(hv, i, rot);
    const int row0 = re.row0;  // history row of entry k
    // The row's touching entries land in the batch's slots directly (the flush above left
    // room for the whole row).
    const int c0 = cb.n;
    const SplitOut slots{cb.k + c0, cb.j + c0, cb.rx + c0, cb.ry + c0, cb.rz + c0, nullptr};
    int kept = 0;
    if constexpr (Mode == NearMode::Use) {
      cb.n += split_row<H, rot, false>(hv, b, bi, list, hist, fh, qh, row0, re.e0, re.e1, slots,
                                       NearEntries{nr.k}, kept);
    } else {
      cb.n += split_row<H, rot, false>(hv, b, bi, list, hist, fh, qh, row0, re.e0, re.e1, slots,
                                       ListEntries{nr.k + list.pair_begin(i), nr.skin}, kept);
      nr.count[i] = kept;
    }
    for (int c = c0; c < cb.n; ++c) {
      const int r = row0 + cb.k[c];  // history row
      cb.k[c] = r;
      const Body bj = load_body(hv, cb.j[c], rot);
      cb.set_contact<L>(c, bi, bj, r3, hist + r * H);
      if (!cb.uniform) cb.set_params(c, Law::pair(m, bi.s, bj.s));
    }
    cb.row_i[cb.rows] = i, cb.row_end[cb.rows] = cb.n, ++cb.rows;
  }
  flush();
}
#endif

// Which force pass a backend uses: one pass by slabs where threads are few and share
// memory, the two passes on a device.
template <class ExecSpace>
constexpr bool forces_by_slabs() {
  return std::is_same_v<typename ExecSpace::memory_space, Kokkos::HostSpace>;
}

#if GRANULAR_CONTACT_BATCH
// compute_pair_forces with the touching contacts evaluated in batches (ContactBatch), for the
// multi-contact laws whose hook records what the law gave (Hook::batchable: Hook::record(k, s,
// fn) with the contact's frame and normal force) and at most corrects the normal law's overlap
// (Hook::corrected: Hook::corrections(k, c0, c1), the normal law then sees ((delta + c0) + c1)
// clamped at 0). The same rows, histories and records, bit for bit: the lanes round as the
// scalar law does, and every contact's outputs go to its own entry row, so a batch may end
// anywhere in a particle's row.
template <class ExecSpace, class Model, class HistoryView, class PairView, class Hook>
void compute_pair_forces_batched(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                                 const HistoryView& history, const PairView& pair,
                                 const PeriodicBox& box, const Model& m,
                                 const double strain_rate[3], double dt, const Hook& hook) {
  constexpr int H = Model::history;
  using Law = ContactBatchLaw<Model>;
  constexpr BatchLaw L = Law::law;
  static_assert(H == batch_history(L) && Model::rotations, "the batched law has a spring");
  constexpr int kTask = 64;  // particles per task
  const HostParticleViews hv(p);
  const HostListRows list(nl);
  double* const hist = history.data();
  const PeriodicBox b = box;
  const double rt[3] = {strain_rate[0], strain_rate[1], strain_rate[2]};
  const bool uniform = Law::uniform(m);
  const BatchParams up = Law::pair(m, 0, 0);
  const BatchForm form = Law::form(m);
  const int n = p.n, tasks = (n + kTask - 1) / kTask;
  using Policy = Kokkos::RangePolicy<ExecSpace, Kokkos::Schedule<Kokkos::Dynamic>>;
  Kokkos::parallel_for(Hook::batched_label, Policy(0, tasks), [=](const int t) {
    const double r3[3] = {rt[0], rt[1], rt[2]};
    ContactBatch cb;
    if (uniform) cb.set_uniform(up);
    cb.form = form;
    int entry[ContactBatch::kCap], si[ContactBatch::kCap], sj[ContactBatch::kCap];
    auto flush = [&] {
      cb.evaluate<L, true, Hook::corrected>(dt);
      for (int c = 0; c < cb.n; ++c) {
        const int k = entry[c];
        pair(k, 0) = cb.f0[c], pair(k, 1) = cb.f1[c], pair(k, 2) = cb.f2[c];
        pair(k, 3) = cb.q0[c], pair(k, 4) = cb.q1[c], pair(k, 5) = cb.q2[c];
        pair(k, 6) = cb.p0[c], pair(k, 7) = cb.p1[c], pair(k, 8) = cb.p2[c];
        cb.store_history<L>(c, hist + cb.k[c] * H);
        PairState s{};
        s.n[0] = cb.n0[c], s.n[1] = cb.n1[c], s.n[2] = cb.n2[c];
        s.delta = cb.overlap[c];
        s.ai = cb.ai[c], s.aj = cb.aj[c];
        s.si = si[c], s.sj = sj[c];
        s.wall = false;
        hook.record(k, s, cb.fn[c]);
      }
      cb.n = cb.rows = 0;
    };
    const int i1 = (t + 1) * kTask < n ? (t + 1) * kTask : n;
    for (int i = t * kTask; i < i1; ++i) {
      const Body bi = load_body(hv, i, true);
      const int row0 = list.pair_begin(i) - list.offsets(i);  // history row of entry k
      for (int k = list.offsets(i); k < list.owned_end(i); ++k) {
        const int j = list.neighbors(k);
        double rx, ry, rz, r2;
        if (!touching(hv, b, bi, j, rx, ry, rz, r2)) {  // as compute_pair_forces
          for (int c = 0; c < 9; ++c) pair(k, c) = 0.0;
          forget_history<H>(hist, row0 + k);
          hook.apart(k);
          continue;
        }
        const int c = cb.n++;
        entry[c] = k, cb.k[c] = row0 + k, cb.j[c] = j;
        cb.rx[c] = rx, cb.ry[c] = ry, cb.rz[c] = rz;
        const Body bj = load_body(hv, j, true);
        cb.set_contact<L>(c, bi, bj, r3, hist + (row0 + k) * H);
        if (!cb.uniform) cb.set_params(c, Law::pair(m, bi.s, bj.s));
        si[c] = bi.s, sj[c] = bj.s;
        if constexpr (Hook::corrected) hook.corrections(k, cb.c0[c], cb.c1[c]);
        if (cb.n == ContactBatch::kCap) flush();
      }
    }
    if (cb.n > 0) flush();
  });
}
#endif

// compute_pair_forces through the batch where it applies (a host backend with AVX, a law the
// batch has, a batchable hook, `batched`); returns whether it did.
template <class ExecSpace, class Model, class HistoryView, class PairView, class Hook>
bool pair_forces_batched_if_possible(const Particles<ExecSpace>& p,
                                     const NeighborList<ExecSpace>& nl, const HistoryView& history,
                                     const PairView& pair, const PeriodicBox& box,
                                     const Model& model, const double strain_rate[3], double dt,
                                     const Hook& hook, bool batched) {
#if GRANULAR_CONTACT_BATCH
  if constexpr (forces_by_slabs<ExecSpace>() && ContactBatchLaw<Model>::available &&
                Hook::batchable) {
    if (batched && cpu_has_avx() && ContactBatchLaw<Model>::usable(model)) {
      compute_pair_forces_batched(p, nl, history, pair, box, model, strain_rate, dt, hook);
      return true;
    }
  }
#endif
  (void)p, (void)nl, (void)history, (void)pair, (void)box, (void)model, (void)strain_rate;
  (void)dt, (void)hook, (void)batched;
  return false;
}

// The slabs of the one-pass kernel below, in three rounds (see there), reading the rows as
// Mode says.
template <class ExecSpace, class Model, NearMode Mode>
void one_pass_slabs(const HostParticleViews& hv, const PeriodicBox& b, const Model& m,
                    const HostListRows& list, const HostArray<const int>& order,
                    const HostArray<const int>& slab_begin, double* hist, const HostVec3& fh,
                    const HostVec3& qh, const double rate[3], double dt, const NearRows& nr,
                    int slabs, bool batched) {
  const int rounds = slabs >= 3 ? 3 : 1;
  using Policy = Kokkos::RangePolicy<ExecSpace, Kokkos::Schedule<Kokkos::Dynamic>>;
  const double rt[3] = {rate[0], rate[1], rate[2]};
#if GRANULAR_CONTACT_BATCH
  // The frictionless linear law reads the stream where it can, and records it after the
  // rows below.
  NearStream* const nst = is_frictionless_linear<Model> ? nr.stream : nullptr;
  const bool normal_stream = batched && nst != nullptr && near_stream_usable(m);
  if constexpr (is_frictionless_linear<Model>) {
    if (Mode == NearMode::Use && normal_stream && nst->ready) {
      const int *si = nst->i.data(), *sj = nst->j.data(), *sb = nst->begin.data();
      const int *se = nst->empty.data(), *eb = nst->empty_begin.data();
      const LinearNormal::Params pn = m.normal.table(0, 0);
      ++nst->reads;
      for (int r = 0; r < rounds; ++r) {
        const int tasks = (slabs - r + rounds - 1) / rounds;
        Kokkos::parallel_for("dem::compute_forces::near_stream", Policy(0, tasks),
                             [=](const int t) {
                               const int s = t * rounds + r;
                               near_stream_slab_normal(hv, b, pn, si, sj, sb[s], sb[s + 1], se,
                                                       eb[s], eb[s + 1], fh, rt);
                             });
      }
      return;
    }
  }
  if constexpr (ContactBatchLaw<Model>::available) {
    if (batched && cpu_has_avx() && ContactBatchLaw<Model>::usable(m)) {
      NearStream* const st = nr.stream;
      const bool stream = st != nullptr && near_stream_usable(m);
      if (Mode == NearMode::Use && stream && st->ready) {
        const int *si = st->i.data(), *sj = st->j.data(), *sr = st->r.data();
        const int *sb = st->begin.data(), *se = st->empty.data(), *eb = st->empty_begin.data();
        constexpr BatchLaw L = ContactBatchLaw<Model>::law;
        const BatchParams pp = ContactBatchLaw<Model>::pair(m, 0, 0);
        const BatchForm form = ContactBatchLaw<Model>::form(m);
        const double* const pack = nr.pack;
        ++st->reads;
        st->packed_reads += pack != nullptr;
        for (int r = 0; r < rounds; ++r) {
          const int tasks = (slabs - r + rounds - 1) / rounds;
          Kokkos::parallel_for(
              "dem::compute_forces::near_stream", Policy(0, tasks), [=](const int t) {
                const int s = t * rounds + r;
                if (pack != nullptr)
                  near_stream_slab<L, true>(hv, b, pp, form, si, sj, sr, sb[s], sb[s + 1], se,
                                            eb[s], eb[s + 1], hist, fh, qh, rt, dt, pack);
                else
                  near_stream_slab<L, false>(hv, b, pp, form, si, sj, sr, sb[s], sb[s + 1], se,
                                             eb[s], eb[s + 1], hist, fh, qh, rt, dt, nullptr);
              });
        }
        return;
      }
      for (int r = 0; r < rounds; ++r) {
        const int tasks = (slabs - r + rounds - 1) / rounds;
        Kokkos::parallel_for("dem::compute_forces::slabs", Policy(0, tasks), [=](const int t) {
          const int slab = t * rounds + r;
          one_pass_rows_batched<Model, Mode>(hv, b, m, list, order, hist, fh, qh, rt, dt, nr,
                                             slab_begin(slab), slab_begin(slab + 1));
        });
      }
      if (Mode == NearMode::Record && stream)
        record_near_stream<ExecSpace>(*st, list, order, slab_begin, slabs, nr);
      return;
    }
  }
#else
  (void)batched;
#endif
  for (int r = 0; r < rounds; ++r) {
    const int tasks = (slabs - r + rounds - 1) / rounds;
    Kokkos::parallel_for(
        "dem::compute_forces::slabs", Policy(0, tasks), KOKKOS_LAMBDA(const int t) {
          const int slab = t * rounds + r;
          const double r3[3] = {rt[0], rt[1], rt[2]};
          for (int q = slab_begin(slab); q < slab_begin(slab + 1); ++q)
            one_pass_row<Model, Mode>(hv, b, m, list, hist, fh, qh, r3, dt, nr, order(q));
        });
  }
#if GRANULAR_CONTACT_BATCH
  if (Mode == NearMode::Record && normal_stream)
    record_near_stream<ExecSpace>(*nst, list, order, slab_begin, slabs, nr, false);
#endif
}

// One pass, for host backends: the owner of each contact evaluates it, adds the force to
// itself and scatters the reaction to its partner at once, as a serial code with a half
// list would. No per-contact force array, no second sweep over the list. Writes to the
// partner cannot race because threads work on slabs of the neighbour list
// (NeighborList::slab_begin) three slabs apart: a contact joins particles of the same or
// adjacent slabs, so concurrent slabs never touch the same particle. Each slab is swept by
// one thread in cell order, so every particle's sum has a fixed order whatever the thread
// count. (A device has too few slabs to fill it; it keeps the two passes above.)
// `batched`: laws with a batched evaluation (ContactBatchLaw) use it where the processor has
// AVX; false forces the contact-by-contact rows (tests compare the two).
// `started`: f and torque already hold the damping terms (set by the integrator's pass,
// kick_drift with DampingStart), so the sweep that sets them is left out.
// `near`, `near_mode`: the near list's rows (see NearRows), recorded by this pass or read by
// it; the caller keeps track of whether they are still valid.
template <class ExecSpace, class Model, class HistoryView>
void compute_forces_by_slabs(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                             const HistoryView& history, const PeriodicBox& box, const Model& model,
                             const Damping& damping, const double strain_rate[3], double dt,
                             const NearRows& near, NearMode near_mode, bool batched = true,
                             bool started = false) {
  if (p.n > 0 && (near.k == nullptr || near.count == nullptr))
    throw std::logic_error("compute_forces_by_slabs: no room for the near list's rows");
  const ParticleViews<ExecSpace> pv(p);
  const HostParticleViews hv(p);
  auto f = p.f, torque = p.torque;
  const HostVec3 fh{p.f.data()}, qh{p.torque.data()};
  const HostListRows list(nl);
  const HostArray<const int> order{nl.cell_order().data()}, slab_begin{nl.slab_begin().data()};
  double* const hist = history.data();
  const PeriodicBox b = box;
  const Model m = model;
  const double gb = damping.translational, gr = damping.rotational;
  const double rate[3] = {strain_rate[0], strain_rate[1], strain_rate[2]};
  if (!started)
    Kokkos::parallel_for(
        "dem::compute_forces::damping", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i) {
          // Plain ifs on compile-time constants (folded all the same): nvcc's extended
          // lambdas cannot first-capture a variable inside if constexpr.
          constexpr bool rot = Model::rotations;
          for (int d = 0; d < 3; ++d) f(i, d) = -gb * pv.v(i, d);
          if (rot)
            for (int d = 0; d < 3; ++d) torque(i, d) = -gr * pv.w(i, d);
        });
  const int slabs = nl.num_slabs();
  NearRows nr = near;
  if (nr.stream != nullptr) {
    if (near_mode == NearMode::Record) nr.stream->ready = false;  // until recorded again
    if (!near_stream_indexable(nl.num_pairs(), p.n)) nr.stream = nullptr;
  }
  if (near_mode == NearMode::Use)
    one_pass_slabs<ExecSpace, Model, NearMode::Use>(hv, b, m, list, order, slab_begin, hist, fh, qh,
                                                    rate, dt, nr, slabs, batched);
  else
    one_pass_slabs<ExecSpace, Model, NearMode::Record>(hv, b, m, list, order, slab_begin, hist, fh,
                                                       qh, rate, dt, nr, slabs, batched);
}

template <class ExecSpace, class Model, class HistoryView, class PairView>
void compute_forces(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                    const HistoryView& history, const PairView& pair, const PeriodicBox& box,
                    const Model& model, const Damping& damping, const double strain_rate[3],
                    double dt, bool two_pass, const NearRows& near, NearMode near_mode,
                    bool batched = true, bool thread_per_particle = false, bool started = false,
                    const RowFlags<ExecSpace>& flags = {},
                    const FixedPositions<ExecSpace>* fixed = nullptr) {
  if (!two_pass && !fixed) {
    if constexpr (forces_by_slabs<ExecSpace>()) {
      compute_forces_by_slabs(p, nl, history, box, model, damping, strain_rate, dt, near, near_mode,
                              batched, started);
      return;
    }
  }
  compute_contact_rows(p, nl, history, pair, box, model, strain_rate, dt, thread_per_particle,
                       flags, fixed);
  gather_contact_forces<ExecSpace, Model>(p, nl, pair, damping, nl.pair_begin(), nl.pair_row(),
                                          "dem::compute_forces::gather_rows", flags);
}

}  // namespace granular
