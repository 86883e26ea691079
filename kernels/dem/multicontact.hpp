// Multi-contact (non-binary) force laws for soft particles (docs/model_multicontact.md), layered
// on the classical contact passes through their hooks:
//   MC-strain: each contact's normal force uses its overlap plus the displacement that the
//     other contacts of both particles cause there (forces of the previous step: explicit);
//   MC-stress: each contact's normal force gets beta nu A P, P the pressure of the two
//     particles' stresses from a first, classical pass.
// Opt-in per scene: DemSystem picks the classical kernels or these at run time, outside the
// kernels, and every kernel here is compiled for one law only.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "core/dem/walls.hpp"
#include "core/run/error.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/contact_forces.hpp"
#include "kernels/dem/contact_history.hpp"
#include "kernels/dem/neighbor_list.hpp"
#include "kernels/dem/wall_forces.hpp"

namespace granular {

// Scene options. Materials are per species (the species slots of the contact model); only
// the particles' own species are read: a rigid wall deforms nothing and carries no stress.
struct MultiContact {
  enum Mode { None, Strain, Stress } mode = None;
  double gamma = 1;  // MC-strain prefactor (an input: the source's guidance on it is ambiguous)
  double beta = 1;   // MC-stress prefactor
  // MC-stress: whether the pair's own contact enters both particles' stresses (the source's
  // pseudo-code) or not (default: then two isolated spheres are exactly classical Hertz).
  bool own_contact = false;
  // MC-stress: P from the sum of the two stress traces / 3 (pseudo-code, default) or from
  // their mean (/ 6).
  bool mean = false;
  // Whether particle-wall contacts take part (they deform the particle like any other).
  bool walls = true;
  // MC-stress: the area A of beta nu A P, which the source names without a formula
  // (docs/model_multicontact.md): the Hertz contact area pi R* delta (default, the literal
  // reading) or a particle-scale area pi R*^2.
  enum Area { HertzArea, ParticleArea } area = HertzArea;
  double young[kMaxSpecies] = {}, poisson[kMaxSpecies] = {};

  // Throws InputError unless the materials of the species in use fit the chosen law.
  void validate(const bool used[kMaxSpecies]) const {
    if (mode == None) return;
    if (mode == Strain && !std::isfinite(gamma))
      throw InputError("multicontact: gamma must be finite");
    if (mode == Stress && !std::isfinite(beta))
      throw InputError("multicontact: beta must be finite");
    for (int s = 0; s < kMaxSpecies; ++s) {
      if (!used[s]) continue;
      const std::string which = "multicontact: species " + std::to_string(s);
      if (mode == Strain && !(young[s] > 0 && std::isfinite(young[s])))
        throw InputError(which + " needs a positive, finite Young modulus for MC-strain");
      if (!(poisson[s] > -1.0 && poisson[s] <= 0.5))
        throw InputError(which + " needs a Poisson ratio in (-1, 0.5]");
    }
  }
};

// The time-step guard's allowance for MC-stress (docs/model_multicontact.md §6): how much stiffer
// than its pair law a contact can be. Contact c of particles i and j gains
//   beta nu pi R* delta_c f (T_i / V_i + T_j / V_j),  f = 1/3 (1/6 with `mean`),
// T the sum of lever x normal force over the particle's other contacts. Bounded with R* <= a,
// levers <= a, every contact at the largest overlap delta = mu a and carrying the Hertz force
// (2/3) k delta, its derivatives sum (a row of the contact Jacobian) to
//   by its own overlap, through the area:          beta nu f mu (Z - 1) k
//   by the 2 (Z - 1) other overlaps, through T:    (3/2) beta nu f mu (Z - 1) k
// against k for the pair law alone (Gershgorin). Z = 12, the kissing number of equal spheres;
// with `own_contact` the pair's own term counts as one more. MC-strain adds no instantaneous
// stiffness: its correction uses the previous step's forces, and the pair law is evaluated at
// the corrected overlap, which the run keeps below max_overlap (DemSystem::check_health).
// With the particle-scale area A = pi R*^2 the area no longer grows with the contact's own
// overlap, and A is at most 1/mu times the Hertz area at the bound: the second term alone,
// without the factor mu, (3/2) beta nu f (Z - 1) k.
inline double stiffness_factor(const MultiContact& mc, double max_overlap) {
  if (mc.mode != MultiContact::Stress) return 1.0;
  constexpr double kissing = 12;
  double nu = 0;
  for (double v : mc.poisson) nu = std::max(nu, v);
  const double f = mc.mean ? 1.0 / 6.0 : 1.0 / 3.0;
  const double others = mc.own_contact ? kissing : kissing - 1;
  if (mc.area == MultiContact::ParticleArea) return 1.0 + 1.5 * mc.beta * nu * f * others;
  return 1.0 + 2.5 * mc.beta * nu * f * max_overlap * others;
}

// Extra overlap at contact c of a particle caused by the normal force f_k at its contact k
// (MC-strain):
//   delta_(k->c) = -gamma (1 + nu) f_k / (2 pi E d) [ (n_k.u)(n_c.u) + (3 - 4 nu) n_k.n_c
//                  - (1 - 2 nu) (n_k + u).n_c / (1 + n_k.u) ]
// pref = -gamma (1 + nu)/(2 pi E). Contact points sit mid-overlap, at x = centre - lambda n
// with lambda = a - delta/2 and n the particle's INWARD normal there (from the partner into
// the particle, the direction of the repulsive force); u is the unit vector from point k to
// point c, d their distance. With inward normals n_k.u = (lambda_k - lambda_c n_k.n_c)/d,
// which is >= 0 for equal levers: 1 + n_k.u >= 1 on a sphere, and it nears 0 only for two
// contacts in nearly the same direction at very different depths, which two partners cannot
// produce. With outward normals the denominator would vanish for diametrically opposite
// contacts (n_k.u = -1), the most common pair of contacts in a squeezed row.
// This is the law's definition in vector form; the passes sum it through strain_pair
// (kernels/contact/lane_law.inc), both directions of a pair at once, which the tests hold to it.
KOKKOS_INLINE_FUNCTION double strain_overlap(const double nk[3], double lk, double fk,
                                             const double nc[3], double lc, double pref,
                                             double nu) {
  const double r[3] = {lk * nk[0] - lc * nc[0], lk * nk[1] - lc * nc[1],
                       lk * nk[2] - lc * nc[2]};  // x_c - x_k
  const double d = norm3(r);
  if (!(d > 0.0)) return 0.0;  // coincident points have no direction: no defined correction
  const double inv = 1.0 / d;
  const double u[3] = {r[0] * inv, r[1] * inv, r[2] * inv};
  const double nku = dot3(nk, u), ncu = dot3(nc, u), nkc = dot3(nk, nc);
  const double bracket =
      nku * ncu + (3.0 - 4.0 * nu) * nkc - (1.0 - 2.0 * nu) * (nkc + ncu) / (1.0 + nku);
  return pref * fk * inv * bracket;
}

// strain_pair (kernels/contact/lane_law.inc): strain_overlap for both directions of a pair of
// contacts of one particle at once, for one lane of doubles and for four.

// The sums of MC-strain over the contacts q = 0..nq-1 of one particle: corr(q) += the overlap
// every other contact with a force causes at q, in ascending order of that contact, each pair
// of contacts visited once (strain_pair). load(q, n, lever, f) gives contact q (lever 0: not
// touching, skipped); add(q, v) adds to its sum, which starts at zero.
template <class Load, class Add>
KOKKOS_INLINE_FUNCTION void strain_sums(int nq, double pref, double nu, const Load& load,
                                        const Add& add) {
  for (int a = 0; a < nq; ++a) {
    double na[3], la, fa;
    load(a, na, la, fa);
    if (la == 0.0) continue;
    for (int b = a + 1; b < nq; ++b) {
      double nb[3], lb, fb;
      load(b, nb, lb, fb);
      if (lb == 0.0 || (fa == 0.0 && fb == 0.0)) continue;
      double g_ab, g_ba;
      strain_pair(na, la, nb, lb, nu, g_ab, g_ba);
      if (fa != 0.0) add(b, pref * fa * g_ab);
      if (fb != 0.0) add(a, pref * fb * g_ba);
    }
  }
}

// The model's evaluation with the normal law fed a corrected overlap (clamped at 0), the
// tangential and rolling laws the geometric state: the correction is a normal displacement
// and moves neither the contact point nor the tangential spring's geometry.
// Mirrors ContactModel::evaluate, which has no way to give its parts different states.
template <class Model>
KOKKOS_INLINE_FUNCTION void evaluate_with_normal_overlap(const Model& m, const PairState& s,
                                                         double delta_eff, double dt, double* h,
                                                         PairForce& out) {
  PairState sn = s;
  sn.delta = delta_eff > 0.0 ? delta_eff : 0.0;
  out.fn = m.normal.force(sn, h + Model::normal_offset);
  for (int d = 0; d < 3; ++d) out.f[d] = out.fn * s.n[d];
  if constexpr (Model::tangential_type::active) {
    m.tangential.force(s, m.coulomb_normal(sn, h, out.fn), dt, h + Model::tangential_offset,
                       out.ft);
    for (int d = 0; d < 3; ++d) out.f[d] += out.ft[d];
    double nxf[3];
    cross3(s.n, out.ft, nxf);
    const double li = s.ai - 0.5 * s.delta, lj = s.aj - 0.5 * s.delta;
    for (int d = 0; d < 3; ++d) out.q[d] = -li * nxf[d], out.qj[d] = -lj * nxf[d];
  }
  if constexpr (Model::rolling_type::active) {
    double qr[3] = {0, 0, 0};
    m.rolling.torque(s, m.coulomb_normal(sn, h, out.fn), dt, h + Model::rolling_offset, qr);
    for (int d = 0; d < 3; ++d) out.q[d] += qr[d], out.qj[d] -= qr[d];
  }
}

#if GRANULAR_CONTACT_BATCH
// strain_sums over a particle's touching contacts held as arrays (normal n0 n1 n2, lever l,
// previous force f; padded by three entries), the partners b of each contact a taken four
// at a time: strain_pair forms every lane as it forms one double, and the
// terms are added in strain_sums' order, so the same bits. Only where cpu_has_avx().
GRANULAR_AVX inline void strain_sums_avx(int nt, double pref, double nu, const double* n0,
                                         const double* n1, const double* n2, const double* l,
                                         const double* f, double* corr) {
  using V = simd4::V;
  const V vnu = simd4::splat(nu);
  for (int a = 0; a < nt; ++a) {
    const double fa = f[a];
    const V na[3] = {simd4::splat(n0[a]), simd4::splat(n1[a]), simd4::splat(n2[a])};
    const V la = simd4::splat(l[a]);
    // Contact a's sum in a register from here on (it already holds the terms of the contacts
    // before a): the same additions in the same order, without a store and reload per term,
    // which the compiler must otherwise assume corr[b] may alias.
    double own = corr[a];
    for (int b0 = a + 1; b0 < nt; b0 += 4) {
      const V nb[3] = {simd4::load(n0 + b0), simd4::load(n1 + b0), simd4::load(n2 + b0)};
      V g_ab, g_ba;
      strain_pair(na, la, nb, simd4::load(l + b0), vnu, g_ab, g_ba);
      double ab[4], ba[4];
      simd4::store(ab, g_ab), simd4::store(ba, g_ba);
      const int lanes = nt - b0 < 4 ? nt - b0 : 4;
      for (int q = 0; q < lanes; ++q) {
        const int b = b0 + q;
        if (fa == 0.0 && f[b] == 0.0) continue;
        if (fa != 0.0) corr[b] += pref * fa * ab[q];
        if (f[b] != 0.0) own += pref * f[b] * ba[q];
      }
    }
    corr[a] = own;
  }
}
#endif

namespace multicontact {

// Column indices are enumerators, not constexpr variables: a View's operator() takes its
// indices by reference, and nvcc has no device copy of a namespace-scope variable to bind.
// Columns of the MC-strain scratch per list entry (each particle's view of its contact):
// inward normal (3), lever lambda (0: not touching), previous normal force, correction S.
enum : int { kSN = 0, kSLever = 3, kSForce = 4, kSCorr = 5 };
constexpr int kStrainEntryColumns = 6;
// Columns per (particle, wall) of MC-strain: previous normal force (kept across steps and
// reordered with the particles), then scratch: correction, inward normal (3), lever.
enum : int { kWForce = 0, kWCorr = 1, kWN = 2, kWLever = 5 };
constexpr int kStrainWallColumns = 6;
// Touching contacts of one particle MC-strain sums from the stack (more: from the rows).
constexpr int kStrainStackContacts = 32;
// Columns of the MC-stress rows per owner entry: l.f seen from i and from j (each particle's
// branch vector dotted with the force on it), normal n (3), beta nu A.
enum : int { kTi = 0, kTj = 1, kTN = 2, kTCoef = 5 };
constexpr int kStressEntryColumns = 6;

// Per species: the prefactor -gamma (1 + nu)/(2 pi E) of MC-strain, and nu (a named type:
// device lambdas may not capture function-local types).
struct StrainMaterials {
  double pref[kMaxSpecies], nu[kMaxSpecies];
};

KOKKOS_INLINE_FUNCTION double sphere_volume(double a) { return 4.0 / 3.0 * M_PI * a * a * a; }
// The length L of the MC-stress area A = pi R* L: the overlap delta (the Hertz contact area)
// or R* itself (a particle-scale area, MultiContact::ParticleArea).
KOKKOS_INLINE_FUNCTION double stress_area_length(bool particle_area, const PairState& s) {
  return particle_area ? reduced_radius(s) : s.delta;
}

// Pair pass of MC-strain: the normal law sees delta + S_i(c) + S_j(c), the corrections both
// bodies' other contacts cause at the contact (both spheres deform, each with its own E, nu;
// their displacements add up as for two Hertz half-spaces); the normal force is stored as
// the next evaluation's f_k. That is the force the contact applied: corrected, dashpot
// included and signed (the elastic field is linear in the load, so a briefly tensile contact
// pulls the others' surfaces the other way).
template <class Mem>
struct StrainPairHook {
  static constexpr bool active = true;
  static constexpr const char* label = "dem::multicontact::strain_pairs";
  // The batch evaluates it with the corrections handed over (compute_pair_forces_batched).
  static constexpr bool batchable = true, corrected = true;
  static constexpr const char* batched_label = "dem::multicontact::strain_pairs_batched";
  Kokkos::View<double**, Kokkos::LayoutRight, Mem> scratch, prev;
  Kokkos::View<int*, Mem> mirror;
  template <class Model>
  KOKKOS_INLINE_FUNCTION void evaluate(const Model& m, int k, const PairState& s, double dt,
                                       double* h, PairForce& out) const {
    const double delta_eff = s.delta + scratch(k, kSCorr) + scratch(mirror(k), kSCorr);
    evaluate_with_normal_overlap(m, s, delta_eff, dt, h, out);
    record(k, s, out.fn);
  }
  KOKKOS_INLINE_FUNCTION void corrections(int k, double& c0, double& c1) const {
    c0 = scratch(k, kSCorr), c1 = scratch(mirror(k), kSCorr);
  }
  KOKKOS_INLINE_FUNCTION void record(int k, const PairState&, double fn) const { prev(k, 0) = fn; }
  KOKKOS_INLINE_FUNCTION void apart(int k) const { prev(k, 0) = 0.0; }
};

// Wall pass of MC-strain: the wall is rigid, so only the particle's correction applies.
template <class Mem>
struct StrainWallHook {
  static constexpr bool active = true;
  static constexpr const char* label = "dem::multicontact::strain_walls";
  Kokkos::View<double**, Kokkos::LayoutRight, Mem> wall;
  template <class Model>
  KOKKOS_INLINE_FUNCTION void evaluate(const Model& m, int i, int w, const PairState& s, double dt,
                                       double* h, PairForce& out) const {
    constexpr int C = kStrainWallColumns;
    evaluate_with_normal_overlap(m, s, s.delta + wall(i, w * C + kWCorr), dt, h, out);
    wall(i, w * C + kWForce) = out.fn;
  }
  KOKKOS_INLINE_FUNCTION void apart(int i, int w) const {
    wall(i, w * kStrainWallColumns + kWForce) = 0.0;
  }
};

// First pass of MC-stress: the classical force, and what the stress traces need.
// tr(sigma_i) = (1/V_i) sum_c l^c.f^c with l^c = -lambda_i n (centre to contact point, n the
// inward normal of i) and f^c the force on i; only its normal part counts (l is along n),
// and the tangential force is normal to n by construction, so l.f = -lambda fn exactly.
template <class Mem>
struct StressPairHook {
  static constexpr bool active = true;
  static constexpr const char* label = "dem::multicontact::stress_pairs";
  // The classical law, then a record of its result: the batch may evaluate it (record only).
  static constexpr bool batchable = true, corrected = false;
  static constexpr const char* batched_label = "dem::multicontact::stress_pairs_batched";
  Kokkos::View<double**, Kokkos::LayoutRight, Mem> rows;
  double nu[kMaxSpecies];
  double beta;
  bool particle_area = false;  // MultiContact::ParticleArea
  template <class Model>
  KOKKOS_INLINE_FUNCTION void evaluate(const Model& m, int k, const PairState& s, double dt,
                                       double* h, PairForce& out) const {
    m.evaluate(s, dt, h, out);
    record(k, s, out.fn);
  }
  // What the corrections need of contact k: reads s.n, s.delta, s.ai, s.aj, s.si, s.sj.
  KOKKOS_INLINE_FUNCTION void record(int k, const PairState& s, double fn) const {
    // Seen from j the normal and the force both flip: l_j.f_j = -lambda_j fn as well.
    rows(k, kTi) = -(s.ai - 0.5 * s.delta) * fn;
    rows(k, kTj) = -(s.aj - 0.5 * s.delta) * fn;
    for (int d = 0; d < 3; ++d) rows(k, kTN + d) = s.n[d];
    // Area A = pi R* delta (Hertz) or pi R*^2; nu of the pair: mean of the two species.
    const double nu_ij = 0.5 * (nu[s.si] + nu[s.sj]);
    rows(k, kTCoef) =
        beta * nu_ij * M_PI * reduced_radius(s) * stress_area_length(particle_area, s);
  }
  KOKKOS_INLINE_FUNCTION void apart(int k) const {
    rows(k, kTi) = 0.0, rows(k, kTj) = 0.0, rows(k, kTCoef) = 0.0;
  }
};

// Final wall pass of MC-stress: P = -(tr sigma_i)/3, the wall carrying no particle stress
// (so the same with `mean`: the average over the particles that carry stress is this one's
// pressure); nu is the particle's (a rigid wall has no meaningful nu).
template <class Mem>
struct StressWallHook {
  static constexpr bool active = true;
  static constexpr const char* label = "dem::multicontact::stress_walls";
  Kokkos::View<double**, Kokkos::LayoutRight, Mem> own;  // (n, walls): l.f of each contact
  Kokkos::View<double*, Mem> trace;                      // (n): sum_c l.f (not divided by V)
  double nu[kMaxSpecies];
  double beta, exclude;  // exclude = 1: the contact's own term leaves the trace
  bool particle_area = false;
  template <class Model>
  KOKKOS_INLINE_FUNCTION void evaluate(const Model& m, int i, int w, const PairState& s, double dt,
                                       double* h, PairForce& out) const {
    m.evaluate(s, dt, h, out);
    const double coef =
        beta * nu[s.si] * M_PI * reduced_radius(s) * stress_area_length(particle_area, s);
    const double tr = (trace(i) - exclude * own(i, w)) / sphere_volume(s.ai);
    // sigma = (1/V) sum l (x) f is tension-positive: repulsive contacts make its trace
    // negative. P is compression-positive, so that a squeezed particle gets stiffer.
    const double pressure = -(1.0 / 3.0) * tr;
    const double c = coef * pressure;
    out.fn += c;
    for (int d = 0; d < 3; ++d) out.f[d] += c * s.n[d];
  }
  KOKKOS_INLINE_FUNCTION void apart(int, int) const {}
};

}  // namespace multicontact

// State and passes of the multi-contact laws of one DemSystem: per-contact previous normal
// forces (MC-strain) carried across neighbour-list rebuilds and particle reordering, scratch
// rows, and the sequence of kernels of one force evaluation.
template <class ExecSpace>
class MultiContactForces {
 public:
  using mem = typename ExecSpace::memory_space;
  using rows_view = Kokkos::View<double**, Kokkos::LayoutRight, mem>;
  using int_view = Kokkos::View<int*, mem>;

  const MultiContact& options() const { return opt_; }
  bool active() const { return opt_.mode != MultiContact::None; }

  // Switches a law on (or all off with mode None). Stored forces start from zero: the first
  // evaluation after this is classical for MC-strain.
  void configure(const MultiContact& opt, const Particles<ExecSpace>& p,
                 const NeighborList<ExecSpace>& nl, int nwalls, size_t capacity) {
    opt_ = opt;
    prev_ = ContactHistory<ExecSpace, 1>();
    entry_ = rows_view();
    wall_ = rows_view();
    trace_ = Kokkos::View<double*, mem>();
    if (!active()) return;
    if (opt_.mode == MultiContact::Stress)
      trace_ = Kokkos::View<double*, mem>("dem::multicontact::trace", p.n);
    resize_walls(p.n, nwalls);
    after_build(p, nl, int_view(), capacity);
  }

  // Walls replaced: their stored forces start from zero.
  void resize_walls(int n, int nwalls) {
    if (!active()) return;
    const int rows = opt_.walls && nwalls > 0 ? n : 0;
    const int cols = opt_.mode == MultiContact::Strain ? multicontact::kStrainWallColumns : 1;
    wall_ = rows_view("dem::multicontact::wall", rows, nwalls * cols);
  }

  // Particles reordered (new i = old order(i)): the per-(particle, wall) rows follow.
  void reorder(const int_view& order, int n) {
    if (active()) permute_rows<ExecSpace>(wall_, order, n);
  }

  // After a neighbour-list build: MC-strain's previous forces are carried over by partner
  // identity, exactly as contact history (the rebuild moves nothing, so the force a contact
  // had at the last evaluation is still its previous force); scratch rows grow with the list.
  // `order`: the reordering applied before the build (empty: none).
  void after_build(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                   const int_view& order, size_t capacity) {
    if (!active()) return;
    if (opt_.mode == MultiContact::Strain) prev_.remap(p, nl, order);
    const int cols = opt_.mode == MultiContact::Strain ? multicontact::kStrainEntryColumns
                                                       : multicontact::kStressEntryColumns;
    if (entry_.extent(0) < capacity) entry_ = rows_view("dem::multicontact::entry", capacity, cols);
  }

  // One force evaluation: pair forces, gather, walls and gravity, with the active law.
  template <class Model, class HistoryView, class PairView, class WallHistoryView>
  void compute(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
               const HistoryView& history, const PairView& pair, const PeriodicBox& box,
               const Model& model, const Damping& damping, const double strain_rate[3], double dt,
               const WallSet<ExecSpace>& walls, const WallHistoryView& wall_history,
               WallRecord<ExecSpace>& record, const double gravity[3], bool external,
               bool batched = true) const {
    const int nw = walls.size();
    const int nmc = opt_.walls ? nw : 0;  // walls the law sees
    if (opt_.mode == MultiContact::Strain) {
      strain_corrections(p, nl, box, walls, nmc);
      multicontact::StrainPairHook<mem> hook{entry_, prev_.values(), nl.mirror()};
      if (!pair_forces_batched_if_possible(p, nl, history, pair, box, model, strain_rate, dt, hook,
                                           batched))
        compute_pair_forces(p, nl, history, pair, box, model, strain_rate, dt, hook);
      gather_pair_forces<ExecSpace, Model>(p, nl, pair, damping);
      if (nmc > 0)
        add_external_forces(p, walls.view(), nw, wall_history, record, model, gravity, dt,
                            multicontact::StrainWallHook<mem>{wall_});
      else if (external)
        add_external_forces(p, walls.view(), nw, wall_history, record, model, gravity, dt);
    } else {
      multicontact::StressPairHook<mem> hook;
      hook.rows = entry_;
      hook.beta = opt_.beta;
      hook.particle_area = opt_.area == MultiContact::ParticleArea;
      for (int s = 0; s < kMaxSpecies; ++s) hook.nu[s] = opt_.poisson[s];
      if (!pair_forces_batched_if_possible(p, nl, history, pair, box, model, strain_rate, dt, hook,
                                           batched))
        compute_pair_forces(p, nl, history, pair, box, model, strain_rate, dt, hook);
      stress_traces(p, nl, walls, nmc, wall_history, model);
      stress_corrections(p, nl, pair);
      gather_pair_forces<ExecSpace, Model>(p, nl, pair, damping);
      if (nmc > 0) {
        multicontact::StressWallHook<mem> wh;
        wh.own = wall_, wh.trace = trace_;
        for (int s = 0; s < kMaxSpecies; ++s) wh.nu[s] = opt_.poisson[s];
        wh.beta = opt_.beta, wh.exclude = opt_.own_contact ? 0.0 : 1.0;
        wh.particle_area = opt_.area == MultiContact::ParticleArea;
        add_external_forces(p, walls.view(), nw, wall_history, record, model, gravity, dt, wh);
      } else if (external) {
        add_external_forces(p, walls.view(), nw, wall_history, record, model, gravity, dt);
      }
    }
  }

  // The passes below are public only because nvcc rejects extended lambdas whose enclosing
  // member function is private; they are not meant to be called from outside.

  // MC-strain, before the pair pass: each contact is described for both its particles (inward
  // normal, lever, previous force; written once per list entry, by the contact's owner), then
  // each particle sums, for each of its contacts (pair entries in list order, then walls), the
  // overlap its other contacts cause there with its own E and nu, writing only its own rows,
  // in a fixed order: no atomics, thread-count independent.
  void strain_corrections(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                          const PeriodicBox& box, const WallSet<ExecSpace>& walls, int nmc) const {
    using namespace multicontact;
    const ParticleViews<ExecSpace> pv(p);
    auto offsets = nl.offsets(), neighbors = nl.neighbors(), mirror = nl.mirror();
    auto owned_end = nl.owned_end();
    auto entry = entry_, wall = wall_, prev = prev_.values();
    auto wv = walls.view();
    const PeriodicBox b = box;
    StrainMaterials mat;
    for (int s = 0; s < kMaxSpecies; ++s) {
      mat.nu[s] = opt_.poisson[s];
      mat.pref[s] =
          opt_.young[s] > 0 ? -opt_.gamma * (1.0 + mat.nu[s]) / (2.0 * M_PI * opt_.young[s]) : 0.0;
    }
    // Four partners at a time where the host has AVX (the same bits: strain_sums_avx).
    const bool avx = forces_by_slabs<ExecSpace>() && cpu_has_avx();
    (void)avx;
    // Each contact's geometry, by its owner for both sides: the partner's view is the same
    // numbers seen from the other end (n flips, r and delta are the same sums; min_image is odd),
    // so the bits of computing it twice at half the roots and divisions.
    Kokkos::parallel_for(
        "dem::multicontact::strain_geometry", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i) {
          const Body bi = load_body(pv, i, false);
          for (int k = offsets(i); k < owned_end(i); ++k) {
            const int j = neighbors(k), m = mirror(k);
            double rx, ry, rz, r2;
            if (!touching(pv, b, bi, j, rx, ry, rz, r2)) {
              entry(k, kSLever) = 0.0, entry(k, kSCorr) = 0.0;
              entry(m, kSLever) = 0.0, entry(m, kSCorr) = 0.0;
              continue;
            }
            const double r = Kokkos::Experimental::sqrt(r2);
            const double inv = 1.0 / r;
            const double aj = pv.radius(j);
            const double delta = bi.a + aj - r;
            const double n[3] = {rx * inv, ry * inv, rz * inv};
            for (int d = 0; d < 3; ++d) entry(k, kSN + d) = n[d], entry(m, kSN + d) = -n[d];
            entry(k, kSLever) = bi.a - 0.5 * delta;
            entry(m, kSLever) = aj - 0.5 * delta;
            entry(k, kSForce) = entry(m, kSForce) = prev(k, 0);
          }
        });
    Kokkos::parallel_for(
        "dem::multicontact::strain_overlaps", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i) {
          constexpr int C = kStrainWallColumns;
          const Body bi = load_body(pv, i, false);
          const int k0 = offsets(i), k1 = offsets(i + 1);
          for (int w = 0; w < nmc; ++w) {
            PairState s;
            if (!wall_geometry(bi, wv(w), false, s)) {
              wall(i, w * C + kWLever) = 0.0, wall(i, w * C + kWCorr) = 0.0;
              continue;
            }
            for (int d = 0; d < 3; ++d) wall(i, w * C + kWN + d) = s.n[d];
            wall(i, w * C + kWLever) = bi.a - 0.5 * s.delta;
          }
          const double pf = mat.pref[bi.s], nus = mat.nu[bi.s];
          // Contact q of i: entries first (list order), then walls. The touching ones are
          // summed from a copy on the stack; a particle with more of them than it holds
          // (never in a packing of spheres of similar size) sums from the rows, in the same
          // order and to the same bits.
          const int ne = k1 - k0, nq = ne + nmc;
          int nt = 0;
          constexpr int K = kStrainStackContacts, P = K + 3;  // padded for four lanes
          int at[K];
          double t0[P], t1[P], t2[P], tl[P], tf[P], tc[P];
          auto load_row = [&](int q, double n[3], double& lever, double& f) {
            if (q < ne) {
              const int k = k0 + q;
              for (int d = 0; d < 3; ++d) n[d] = entry(k, kSN + d);
              lever = entry(k, kSLever), f = entry(k, kSForce);
            } else {
              const int w = q - ne;
              for (int d = 0; d < 3; ++d) n[d] = wall(i, w * C + kWN + d);
              lever = wall(i, w * C + kWLever), f = wall(i, w * C + kWForce);
            }
          };
          for (int q = 0; q < nq && nt <= K; ++q) {
            double n[3], lever, f;
            load_row(q, n, lever, f);
            if (lever == 0.0) continue;
            if (nt == K) {
              ++nt;  // too many: sum from the rows
              break;
            }
            at[nt] = q;
            t0[nt] = n[0], t1[nt] = n[1], t2[nt] = n[2];
            tl[nt] = lever, tf[nt] = f, tc[nt] = 0.0;
            ++nt;
          }
          auto store = [&](int q, double v) {
            if (q < ne)
              entry(k0 + q, kSCorr) = v;
            else
              wall(i, (q - ne) * C + kWCorr) = v;
          };
          if (nt <= K) {
            bool done = false;
#if GRANULAR_CONTACT_BATCH && !defined(__CUDA_ARCH__)
            if (avx && nt > 1) {
              // The lanes past the last contact repeat it (formed, never added).
              for (int t = nt; t < P; ++t)
                t0[t] = t0[nt - 1], t1[t] = t1[nt - 1], t2[t] = t2[nt - 1], tl[t] = tl[nt - 1],
                tf[t] = tf[nt - 1];
              strain_sums_avx(nt, pf, nus, t0, t1, t2, tl, tf, tc);
              done = true;
            }
#endif
            if (!done)
              strain_sums(
                  nt, pf, nus,
                  [&](int t, double n[3], double& lever, double& f) {
                    n[0] = t0[t], n[1] = t1[t], n[2] = t2[t];
                    lever = tl[t], f = tf[t];
                  },
                  [&](int t, double v) { tc[t] += v; });
            for (int t = 0; t < nt; ++t) store(at[t], tc[t]);
          } else {
            for (int q = 0; q < nq; ++q) store(q, 0.0);
            strain_sums(nq, pf, nus, load_row, [&](int q, double v) {
              if (q < ne)
                entry(k0 + q, kSCorr) += v;
              else
                wall(i, (q - ne) * C + kWCorr) += v;
            });
          }
        });
  }

  // MC-strain: the largest overlap the pair law saw at the last force evaluation, corrected,
  // over the smaller radius (walls: the particle's), the measure the overlap limit applies to;
  // 0 under the other laws. The time-step guard assumes the limit holds for this overlap too.
  double max_corrected_overlap(const Particles<ExecSpace>& p,
                               const NeighborList<ExecSpace>& nl) const {
    using namespace multicontact;
    if (opt_.mode != MultiContact::Strain) return 0.0;
    auto offsets = nl.offsets(), neighbors = nl.neighbors(), mirror = nl.mirror();
    auto owned_end = nl.owned_end();
    auto entry = entry_, wall = wall_;
    auto radius = p.radius;
    const int nmc =
        wall_.extent(0) > 0 ? static_cast<int>(wall_.extent(1)) / kStrainWallColumns : 0;
    double worst = 0.0;
    Kokkos::parallel_reduce(
        "dem::multicontact::max_corrected_overlap", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i, double& m) {
          constexpr int C = kStrainWallColumns;
          const double ai = radius(i);
          for (int k = offsets(i); k < owned_end(i); ++k) {
            const double lever = entry(k, kSLever);
            if (lever == 0.0) continue;  // not touching
            const double aj = radius(neighbors(k));
            const double delta = 2.0 * (ai - lever) + entry(k, kSCorr) + entry(mirror(k), kSCorr);
            const double r = delta / (ai < aj ? ai : aj);
            if (r > m) m = r;
          }
          for (int w = 0; w < nmc; ++w) {
            const double lever = wall(i, w * C + kWLever);
            if (lever == 0.0) continue;
            const double r = (2.0 * (ai - lever) + wall(i, w * C + kWCorr)) / ai;
            if (r > m) m = r;
          }
        },
        Kokkos::Max<double>(worst));
    return worst;
  }

  // MC-stress, after the classical pair pass: sum_c l.f per particle (pair entries in list
  // order, then walls). The normal force of each wall contact is evaluated here once more from
  // a copy of its history (the wall pass comes after the gather and advances it); its l.f is kept
  // so the wall pass can take the contact's own term out of the trace exactly.
  template <class Model, class WallHistoryView>
  void stress_traces(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                     const WallSet<ExecSpace>& walls, int nmc, const WallHistoryView& history,
                     const Model& model) const {
    using namespace multicontact;
    const ParticleViews<ExecSpace> pv(p);
    auto offsets = nl.offsets(), mirror = nl.mirror(), owned_end = nl.owned_end();
    auto rows = entry_, own = wall_;
    auto trace = trace_;
    auto wv = walls.view();
    const Model m = model;
    Kokkos::parallel_for(
        "dem::multicontact::stress_traces", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i) {
          constexpr int H = Model::history;
          constexpr bool rot = Model::rotations;
          (void)history.extent(0);  // nvcc: capture outside the constexpr-if that uses it
          const int k0 = offsets(i), k1 = offsets(i + 1), ko = owned_end(i);
          double t = 0.0;
          for (int k = k0; k < ko; ++k) t += rows(k, kTi);
          for (int k = ko; k < k1; ++k) t += rows(mirror(k), kTj);
          if (nmc > 0) {
            const Body bi = load_body(pv, i, rot);
            for (int w = 0; w < nmc; ++w) {
              PairState s;
              if (!wall_geometry(bi, wv(w), rot, s)) {
                own(i, w) = 0.0;
                continue;
              }
              double h[H > 0 ? H : 1];
              if constexpr (H > 0)
                for (int c = 0; c < H; ++c) h[c] = history(i, w * H + c);
              // The normal force alone: the model's evaluation forms it first, from the same
              // state and history, and the tangential and rolling parts do not change it.
              const double fn = m.normal.force(s, h + Model::normal_offset);
              const double lf = -(s.ai - 0.5 * s.delta) * fn;
              own(i, w) = lf;
              t += lf;
            }
          }
          trace(i) = t;
        });
  }

  // MC-stress, second pass over the owned contacts: f^n += beta nu A P_ij along n, computed
  // once by the owner and gathered by both particles (exact action-reaction).
  // sigma = (1/V) sum l (x) f is tension-positive: repulsive contacts make its trace
  // negative; P is compression-positive (a squeezed particle gets stiffer), hence the minus:
  //   P_ij = -(tr sigma_i + tr sigma_j)/3   (or /6 with `mean`),
  // with the pair's own contact left out of both traces unless `own_contact`.
  template <class PairView>
  void stress_corrections(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
                          const PairView& pair) const {
    using namespace multicontact;
    auto offsets = nl.offsets(), neighbors = nl.neighbors(), owned_end = nl.owned_end();
    auto rows = entry_;
    auto trace = trace_;
    auto radius = p.radius;
    const double factor = opt_.mean ? 1.0 / 6.0 : 1.0 / 3.0;
    const double exclude = opt_.own_contact ? 0.0 : 1.0;
    Kokkos::parallel_for(
        "dem::multicontact::stress_corrections", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i) {
          const double vi = sphere_volume(radius(i));
          for (int k = offsets(i); k < owned_end(i); ++k) {
            const double coef = rows(k, kTCoef);
            if (coef == 0.0) continue;  // not touching
            const int j = neighbors(k);
            const double tri = (trace(i) - exclude * rows(k, kTi)) / vi;
            const double trj = (trace(j) - exclude * rows(k, kTj)) / sphere_volume(radius(j));
            const double c = coef * (-factor * (tri + trj));
            for (int d = 0; d < 3; ++d) pair(k, d) += c * rows(k, kTN + d);
          }
        });
  }

 private:
  MultiContact opt_;
  ContactHistory<ExecSpace, 1> prev_;  // MC-strain: normal force per entry (owner rows)
  rows_view entry_;                    // per list entry: MC-strain or MC-stress columns
  rows_view wall_;                    // per (particle, wall): MC-strain columns, or l.f (MC-stress)
  Kokkos::View<double*, mem> trace_;  // MC-stress: sum_c l.f per particle
};

}  // namespace granular
