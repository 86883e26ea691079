// Contacts evaluated in batches, four per instruction, for the host one-pass force kernel
// (kernels/dem/contact_forces.hpp, compute_forces_by_slabs), for four laws (BatchLaw): the
// linear law of the frictional peer benchmark and the linear element tests (spring-dashpot with
// the constant Coulomb spring), the restitution-damped Hertz-Mindlin law (waves, impacts, the
// Hertz peer benchmark), the visco-elastic Hertz law (Hertz moduli, mixtures) and the
// hysteretic law with the constant Coulomb spring (the cohesive studies); no rolling.
//
// A slab's rows are read in order; the touching contacts of whole rows are gathered into a
// batch (structure of arrays), the batch is evaluated four contacts at a time in AVX
// registers (GCC vector extensions in a function compiled for AVX; the rest of the build
// stays portable, and the batch is used only where the processor reports AVX at run time),
// and the forces are then scattered row by row in list order. The law's parts are the scalar
// law's own, written once over the number type (kernels/contact/lane_law.inc): every lane
// performs the scalar operations in the scalar order (no contraction into FMA, branches
// replaced by selecting between both outcomes, a rare branch skipped only where no lane of a
// vector takes it), and the sums keep the scalar kernel's order, so the trajectories are
// bitwise those of the scalar path, on any processor (tests/kernels/cpu/test_contact_batch.cpp).
// Measured (docs/perf_design_notes.md, CPUs): the batch made the frictional step 1.10-1.14x
// faster, and its refinements (the split writing into the batch's slots, parameters
// broadcast for one species, the rare branches skipped) 1.13-1.18x more; the frictionless
// law, whose evaluation is a few operations, loses to the gather and scatter in two-lane
// SSE2 and in AVX, so its rows stay contact by contact (the near list's stream, which loads
// its inputs without a gather, does evaluate it in lanes: kernels/cpu/near_stream.hpp).
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "kernels/contact/contact_model.hpp"
#include "kernels/cpu/host_simd.hpp"

// The batch exists where host AVX code is compiled.
#define GRANULAR_CONTACT_BATCH GRANULAR_HOST_AVX

namespace granular {

// The laws the batch evaluates: the linear normal spring-dashpot with the constant Coulomb
// spring; the restitution-damped Hertz law with the restitution-damped Mindlin spring (the
// studies' law: kernels/contact/contact_hertz_restitution.hpp, CoulombTangential::
// MindlinRestitution), which also reads the particles' masses; and the visco-elastic Hertz law
// (kernels/contact/contact_hertz.hpp) with the constant or an L-delta Mindlin spring, in the
// form (BatchForm) that every pair shares; and the hysteretic law (kernels/contact/
// contact_hysteretic.hpp) with the constant Coulomb spring, whose history holds delta_max
// ahead of the spring.
enum class BatchLaw { Linear, HertzRestitution, Hertz, Hysteretic };
// Where the spring sits in a contact's history row, and the row's length.
constexpr int batch_spring_at(BatchLaw L) { return L == BatchLaw::Hysteretic ? 1 : 0; }
constexpr int batch_history(BatchLaw L) { return batch_spring_at(L) + 3; }

// The visco-elastic Hertz law's form, one for every pair: the normal force's length (R* or
// a_i + a_j) and the tangential spring's law (Constant, MindlinPairDiameter or
// MindlinReducedRadius).
struct BatchForm {
  bool reduced_radius = false;
  int tangential = CoulombTangential::Constant;
};

// A pair's parameters in the batch's slots: the normal law's two (linear: k_n, gamma_n;
// Hertz: K, alpha; hysteretic: k2, gamma_n), the tangential spring's four (k_t, gamma_t or
// their coefficients, mu_s, mu_d), and the hysteretic law's loading and adhesive stiffnesses.
struct BatchParams {
  double kn = 0, gn = 0, kt = 0, gt = 0, mus = 0, mud = 0;
  double k1 = 0, kc = 0;  // BatchLaw::Hysteretic only
};

namespace contact_batch_detail {
inline bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
inline bool same_bits(const BatchParams& a, const BatchParams& b) {
  return same_bits(a.kn, b.kn) && same_bits(a.gn, b.gn) && same_bits(a.kt, b.kt) &&
         same_bits(a.gt, b.gt) && same_bits(a.mus, b.mus) && same_bits(a.mud, b.mud) &&
         same_bits(a.k1, b.k1) && same_bits(a.kc, b.kc);
}
// Whether every pair's tangential spring follows `law`.
inline bool every_tangential_law(const CoulombTangential& t, int law) {
  for (int a = 0; a < kMaxSpecies; ++a)
    for (int b = 0; b < kMaxSpecies; ++b)
      if (t.table.p[a][b].law != law) return false;
  return true;
}
// Whether every pair has the batch parameters of pair (0, 0), bit for bit (so that
// broadcasting them changes no result, not even the sign of a zero).
template <class Law, class Model>
bool uniform_pairs(const Model& m) {
  const BatchParams p0 = Law::pair(m, 0, 0);
  for (int a = 0; a < kMaxSpecies; ++a)
    for (int b = 0; b < kMaxSpecies; ++b)
      if (!same_bits(Law::pair(m, a, b), p0)) return false;
  return true;
}
}  // namespace contact_batch_detail

// Which models have a batched evaluation (compile time), and whether this instance's
// parameters allow it (run time: the batch limits the spring with the total normal force, and
// evaluates one form of the tangential spring per law).
template <class Model>
struct ContactBatchLaw {
  static constexpr bool available = false;
  static bool usable(const Model&) { return false; }
  static bool uniform(const Model&) { return false; }
};

namespace contact_batch_detail {
// A pair's normal parameters in the batch's slots, per law (BatchParams).
inline BatchParams normal_slots(const LinearNormal::Params& n) { return {n.kn, n.gn}; }
inline BatchParams normal_slots(const HertzRestitutionNormal::Params& n) { return {n.K, n.alpha}; }
inline BatchParams normal_slots(const HertzNormal::Params& n) { return {n.K, n.G}; }
inline BatchParams normal_slots(const HystereticNormal::Params& n) {
  BatchParams p{n.k2, n.gn};
  p.k1 = n.k1, p.kc = n.kc;
  return p;
}

// What every batched law shares: a normal law with the Coulomb spring, its parameters in the
// batch's slots, usable where the spring is limited by the total normal force and every pair's
// spring follows `Tangential`, uniform where every pair has the parameters of pair (0, 0).
// A law with more than one form (the visco-elastic Hertz law) hides usable() and form().
template <class Normal, BatchLaw L, int Tangential>
struct CoulombBatchLaw {
  using Model = ContactModel<Normal, CoulombTangential>;
  static constexpr bool available = GRANULAR_CONTACT_BATCH;
  static constexpr BatchLaw law = L;
  static bool usable(const Model& m) {
    return !m.coulomb_elastic_normal && every_tangential_law(m.tangential, Tangential);
  }
  static BatchParams pair(const Model& m, int a, int b) {
    BatchParams p = normal_slots(m.normal.table.p[a][b]);
    const CoulombTangential::Params& t = m.tangential.table.p[a][b];
    p.kt = t.kt, p.gt = t.gt, p.mus = t.mu_s, p.mud = t.mu_d;
    return p;
  }
  static bool uniform(const Model& m) { return uniform_pairs<ContactBatchLaw<Model>>(m); }
  static BatchForm form(const Model&) { return {}; }
};
}  // namespace contact_batch_detail

template <>
struct ContactBatchLaw<ContactModel<LinearNormal, CoulombTangential>>
    : contact_batch_detail::CoulombBatchLaw<LinearNormal, BatchLaw::Linear,
                                            CoulombTangential::Constant> {
  // Whether every pair has the normal parameters of pair (0, 0), bit for bit (the
  // frictionless law's stream, kernels/cpu/near_stream.hpp).
  static bool uniform_normal(const LinearNormal& l) {
    const LinearNormal::Params& n0 = l.table.p[0][0];
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b) {
        const LinearNormal::Params& n = l.table.p[a][b];
        if (!contact_batch_detail::same_bits(n.kn, n0.kn) ||
            !contact_batch_detail::same_bits(n.gn, n0.gn))
          return false;
      }
    return true;
  }
};
template <>
struct ContactBatchLaw<ContactModel<HertzRestitutionNormal, CoulombTangential>>
    : contact_batch_detail::CoulombBatchLaw<HertzRestitutionNormal, BatchLaw::HertzRestitution,
                                            CoulombTangential::MindlinRestitution> {};
template <>
struct ContactBatchLaw<ContactModel<HystereticNormal, CoulombTangential>>
    : contact_batch_detail::CoulombBatchLaw<HystereticNormal, BatchLaw::Hysteretic,
                                            CoulombTangential::Constant> {};
template <>
struct ContactBatchLaw<ContactModel<HertzNormal, CoulombTangential>>
    : contact_batch_detail::CoulombBatchLaw<HertzNormal, BatchLaw::Hertz,
                                            CoulombTangential::Constant> {
  // One form for every pair, and a spring whose dashpot scales as its stiffness (the
  // restitution-damped spring belongs to HertzRestitutionNormal).
  static bool usable(const Model& m) {
    const BatchForm f = form(m);
    if (m.coulomb_elastic_normal || f.tangential == CoulombTangential::MindlinRestitution)
      return false;
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b)
        if (m.normal.table.p[a][b].reduced_radius != f.reduced_radius) return false;
    return contact_batch_detail::every_tangential_law(m.tangential, f.tangential);
  }
  static BatchForm form(const Model& m) {
    return {m.normal.table.p[0][0].reduced_radius, m.tangential.table.p[0][0].law};
  }
};

#if GRANULAR_CONTACT_BATCH

// The law parts of kernels/contact/lane_law.inc, for four AVX lanes.
#define LANE_T simd4::V
#define LANE_M simd4::M
#define LANE_FN GRANULAR_AVX_INLINE
#include "kernels/contact/lane_law.inc"
#undef LANE_T
#undef LANE_M
#undef LANE_FN

// One batch of touching contacts, structure of arrays. Rows (the owner particle i and the
// end of its contacts in the batch) are never split between batches.
struct ContactBatch {
  static constexpr int kCap = 64;  // contacts; a row with more owned entries goes scalar
  static constexpr int kW = 4;     // lanes per vector: one AVX register
  using V = simd4::V;
  using M = simd4::M;

  int n = 0, rows = 0;
  // One parameter set for every pair (a single species, or equal tables): the parameters are
  // then broadcast from here instead of gathered contact by contact into kn ... mud.
  bool uniform = false;
  BatchParams u;
  BatchForm form;  // the visco-elastic Hertz law's form (BatchLaw::Hertz)
  int row_i[kCap], row_end[kCap];
  int j[kCap], k[kCap];
  // Inputs: geometry and relative motion, radii, spins, parameters, the spring. The squared
  // distance is formed again in the lanes (the scalar law's operations in its order, so the
  // same bits) rather than stored by the split for every listed pair.
  alignas(32) double rx[kCap + kW], ry[kCap + kW], rz[kCap + kW];
  alignas(32) double dv0[kCap + kW], dv1[kCap + kW], dv2[kCap + kW];
  alignas(32) double ai[kCap + kW], aj[kCap + kW];
  alignas(32) double mi[kCap + kW], mj[kCap + kW];  // masses (the Hertz law's only)
  alignas(32) double wi0[kCap + kW], wi1[kCap + kW], wi2[kCap + kW];
  alignas(32) double wj0[kCap + kW], wj1[kCap + kW], wj2[kCap + kW];
  alignas(32) double kn[kCap + kW], gn[kCap + kW], kt[kCap + kW], gt[kCap + kW];
  alignas(32) double mus[kCap + kW], mud[kCap + kW];
  alignas(32) double k1[kCap + kW], kc[kCap + kW];  // BatchLaw::Hysteretic only
  // Spring (in: stored, out: advanced), the hysteretic law's delta_max (in and out), and
  // outputs: force on i, torques on i and j.
  alignas(32) double h0[kCap + kW], h1[kCap + kW], h2[kCap + kW], hd[kCap + kW];
  alignas(32) double f0[kCap + kW], f1[kCap + kW], f2[kCap + kW];
  alignas(32) double q0[kCap + kW], q1[kCap + kW], q2[kCap + kW];
  alignas(32) double p0[kCap + kW], p1[kCap + kW], p2[kCap + kW];
  // Outputs of evaluate<L, true> only: the normal force and the contact frame (normal, overlap),
  // which the multi-contact laws read back (kernels/dem/multicontact.hpp).
  alignas(32) double fn[kCap + kW], n0[kCap + kW], n1[kCap + kW], n2[kCap + kW];
  alignas(32) double overlap[kCap + kW];
  // Inputs of evaluate<L, Frame, true> only: the normal law sees the overlap plus two
  // corrections (MC-strain's displacements of both particles, kernels/dem/multicontact.hpp),
  // ((delta + c0) + c1) clamped at 0; the tangential law and the levers keep the overlap.
  alignas(32) double c0[kCap + kW], c1[kCap + kW];

  GRANULAR_AVX_INLINE static V load(const double* a) { return simd4::load(a); }
  GRANULAR_AVX_INLINE static void store(double* a, V v) { simd4::store(a, v); }
  GRANULAR_AVX_INLINE static V splat(double x) { return simd4::splat(x); }
  GRANULAR_AVX_INLINE static V sel(M m, V a, V b) { return lane_select(m, a, b); }
  // The lanes of a comparison that hold, as bits.
  GRANULAR_AVX_INLINE static int lanes(M m) { return lane_bits(m); }
  // A pair parameter of four lanes: broadcast (uniform) or loaded from the slots at a.
  template <bool Uniform>
  GRANULAR_AVX_INLINE static V par(const double* a, double u) {
    if constexpr (Uniform)
      return splat(u);
    else
      return load(a);
  }

  // Every pair takes p from now on: no per-contact parameters are stored.
  void set_uniform(const BatchParams& p) {
    uniform = true;
    u = p;
  }

  // Slot c's motion, given its separation (rx, ry, rz) already in place: the touching contact
  // of bi (the owner) with bj in a flow of rate r3, and its stored spring h; the relative
  // velocity is formed as pair_geometry forms it. `Masses`: the law reads the masses too.
  template <bool Masses, class Body>
  GRANULAR_ALWAYS_INLINE void set_motion(int c, const Body& bi, const Body& bj, const double r3[3],
                                         const double* h) {
    if constexpr (Masses) mi[c] = bi.m, mj[c] = bj.m;
    dv0[c] = bi.v[0] - bj.v[0] + r3[0] * rx[c];
    dv1[c] = bi.v[1] - bj.v[1] + r3[1] * ry[c];
    dv2[c] = bi.v[2] - bj.v[2] + r3[2] * rz[c];
    ai[c] = bi.a, aj[c] = bj.a;
    wi0[c] = bi.w[0], wi1[c] = bi.w[1], wi2[c] = bi.w[2];
    wj0[c] = bj.w[0], wj1[c] = bj.w[1], wj2[c] = bj.w[2];
    h0[c] = h[0], h1[c] = h[1], h2[c] = h[2];
  }
  // Slot c's motion and stored history, for the law L: h is the contact's history row
  // (delta_max ahead of the spring for the hysteretic law).
  template <BatchLaw L, class Body>
  GRANULAR_ALWAYS_INLINE void set_contact(int c, const Body& bi, const Body& bj, const double r3[3],
                                          const double* h) {
    set_motion<L == BatchLaw::HertzRestitution>(c, bi, bj, r3, h + batch_spring_at(L));
    if constexpr (L == BatchLaw::Hysteretic) hd[c] = h[0];
  }
  // Slot c's advanced history into the contact's history row h.
  template <BatchLaw L>
  GRANULAR_ALWAYS_INLINE void store_history(int c, double* h) const {
    constexpr int at = batch_spring_at(L);
    if constexpr (L == BatchLaw::Hysteretic) h[0] = hd[c];
    h[at] = h0[c], h[at + 1] = h1[c], h[at + 2] = h2[c];
  }
  // Slot c's pair parameters (unless uniform).
  GRANULAR_ALWAYS_INLINE void set_params(int c, const BatchParams& p) {
    kn[c] = p.kn, gn[c] = p.gn, kt[c] = p.kt, gt[c] = p.gt, mus[c] = p.mus, mud[c] = p.mud;
    k1[c] = p.k1, kc[c] = p.kc;
  }

  // Appends the touching contact of bi (the owner) with bj (partner j, history row k) at
  // separation (rx, ry, rz) in a flow of rate r3, with its pair's parameters and stored
  // spring h.
  template <class Body>
  void push(const Body& bi, const Body& bj, int j_, int k_, double rx_, double ry_, double rz_,
            const double r3[3], const BatchParams& p, const double* h) {
    const int c = n++;
    j[c] = j_, k[c] = k_;
    rx[c] = rx_, ry[c] = ry_, rz[c] = rz_;
    set_motion<true>(c, bi, bj, r3, h);
    set_params(c, p);
  }

  // Pads the last vector with copies of the last contact (evaluated, never scattered).
  void pad() {
    if (n == 0) return;
    double* arrays[] = {rx,  ry,  rz, dv0, dv1, dv2, ai,  aj,  mi, mj, wi0, wi1, wi2, wj0,
                        wj1, wj2, kn, gn,  kt,  gt,  mus, mud, k1, kc, h0,  h1,  h2,  hd};
    for (double* a : arrays)
      for (int c = n; c < (n + kW - 1) / kW * kW; ++c) a[c] = a[n - 1];
  }

  // The law L (linear, or the restitution-damped Hertz-Mindlin law), the spring rotated into
  // the tangent plane, and the torques. The operations follow pair_geometry, the normal law's
  // force, CoulombTangential::force (rotate_into_plane, coulomb_spring) and
  // ContactModel::evaluate. Only where cpu_has_avx().
  // `Frame`: also store fn, n0 .. n2 and overlap. `Corrected`: read c0, c1.
  template <BatchLaw L, bool Frame = false, bool Corrected = false>
  void evaluate(double dt) {
    pad();
    if constexpr (Corrected)
      for (int c = n; n > 0 && c < (n + kW - 1) / kW * kW; ++c)
        c0[c] = c0[n - 1], c1[c] = c1[n - 1];
    if (uniform)
      evaluate_lanes<L, true, Frame, Corrected>(dt);
    else
      evaluate_lanes<L, false, Frame, Corrected>(dt);
  }

  // One vector of contacts: the law's inputs (the spring s0..s2 in and out) and outputs.
  struct Lanes {
    V X, Y, Z, ai, aj, d0, d1, d2, wi0, wi1, wi2, wj0, wj1, wj2, s0, s1, s2;
    V mi, mj;                              // masses (read by the Hertz law only)
    V D;                                   // delta_max (the hysteretic law's, in and out)
    V F0, F1, F2, q0, q1, q2, p0, p1, p2;  // force on i, torques on i and j
    V Fn, N0, N1, N2, Dl;                  // normal force, normal and overlap
    V C0, C1;                              // the normal law's corrections (Corrected)
  };
  struct LaneParams {
    V kn, gn, kt, gt, mus, mud;
    V k1, kc;  // BatchLaw::Hysteretic only
  };
  GRANULAR_AVX_INLINE static LaneParams splat(const BatchParams& p) {
    return {splat(p.kn),  splat(p.gn),  splat(p.kt), splat(p.gt),
            splat(p.mus), splat(p.mud), splat(p.k1), splat(p.kc)};
  }

  template <BatchLaw L, bool Uniform, bool Frame, bool Corrected>
  GRANULAR_AVX void evaluate_lanes(double dt) {
    const V vdt = splat(dt);
    for (int c = 0; c < n; c += kW) {
      Lanes l;
      l.X = load(rx + c), l.Y = load(ry + c), l.Z = load(rz + c);
      l.ai = load(ai + c), l.aj = load(aj + c);
      if constexpr (L == BatchLaw::HertzRestitution) l.mi = load(mi + c), l.mj = load(mj + c);
      l.d0 = load(dv0 + c), l.d1 = load(dv1 + c), l.d2 = load(dv2 + c);
      l.wi0 = load(wi0 + c), l.wi1 = load(wi1 + c), l.wi2 = load(wi2 + c);
      l.wj0 = load(wj0 + c), l.wj1 = load(wj1 + c), l.wj2 = load(wj2 + c);
      l.s0 = load(h0 + c), l.s1 = load(h1 + c), l.s2 = load(h2 + c);
      // (k1 and kc are read by the hysteretic law only: the other laws' loads go unused.)
      const LaneParams p{par<Uniform>(kn + c, u.kn),   par<Uniform>(gn + c, u.gn),
                         par<Uniform>(kt + c, u.kt),   par<Uniform>(gt + c, u.gt),
                         par<Uniform>(mus + c, u.mus), par<Uniform>(mud + c, u.mud),
                         par<Uniform>(k1 + c, u.k1),   par<Uniform>(kc + c, u.kc)};
      if constexpr (L == BatchLaw::Hysteretic) l.D = load(hd + c);
      if constexpr (Corrected) l.C0 = load(c0 + c), l.C1 = load(c1 + c);
      law<L, Corrected>(l, p, vdt, form);
      store(h0 + c, l.s0), store(h1 + c, l.s1), store(h2 + c, l.s2);
      if constexpr (L == BatchLaw::Hysteretic) store(hd + c, l.D);
      store(q0 + c, l.q0), store(q1 + c, l.q1), store(q2 + c, l.q2);
      store(p0 + c, l.p0), store(p1 + c, l.p1), store(p2 + c, l.p2);
      store(f0 + c, l.F0), store(f1 + c, l.F1), store(f2 + c, l.F2);
      if constexpr (Frame) {
        store(fn + c, l.Fn), store(overlap + c, l.Dl);
        store(n0 + c, l.N0), store(n1 + c, l.N1), store(n2 + c, l.N2);
      }
    }
  }

  // The law L on one vector of contacts (also the near stream's, kernels/cpu/near_stream.hpp):
  // the parts of kernels/contact/lane_law.inc, composed as ContactModel::evaluate composes them
  // for one contact (pair_geometry, the normal law's force, CoulombTangential::force with the
  // law's spring, the torques). The rare branches are taken only where a lane in `active`
  // needs them: the other lanes (apart pairs of the stream) are not used, and must not send a
  // vector down a branch.
  // `Corrected`: the normal law sees ((delta + C0) + C1) clamped at 0
  // (evaluate_with_normal_overlap, kernels/dem/multicontact.hpp), the rest the overlap itself.
  template <BatchLaw L, bool Corrected = false>
  GRANULAR_AVX_INLINE static void law(Lanes& l, const LaneParams& p, V vdt, const BatchForm& form,
                                      M active = M{-1, -1, -1, -1}) {
    constexpr bool restitution = L == BatchLaw::HertzRestitution;
    const V r[3] = {l.X, l.Y, l.Z};
    const V dv[3] = {l.d0, l.d1, l.d2};
    V n[3], delta, vn;
    contact_frame(r, l.X * l.X + l.Y * l.Y + l.Z * l.Z, l.ai, l.aj, dv, n, delta, vn);
    V dn = delta;  // the normal law's overlap
    if constexpr (Corrected) {
      const V de = delta + l.C0 + l.C1;
      dn = sel(de > splat(0.0), de, splat(0.0));
    }
    V fn, scale{}, mstar{};  // scale: the Mindlin spring's sqrt(L delta)
    if constexpr (restitution) {
      mstar = reduced_pair(l.mi, l.mj);
      const V R = reduced_pair(l.ai, l.aj);
      fn = hertz_restitution_force(p.kn, p.gn, R, mstar, dn, -vn, scale);
      if constexpr (Corrected) scale = lane_sqrt(R * delta);  // the spring's, uncorrected
    } else if constexpr (L == BatchLaw::Hertz) {
      // The lengths as reduced_radius and pair_diameter form them (no wall here), each formed
      // only where the form uses it.
      const bool normal_r = form.reduced_radius;
      const bool spring_r = form.tangential == CoulombTangential::MindlinReducedRadius;
      const V reduced = normal_r || spring_r ? reduced_pair(l.ai, l.aj) : l.ai;
      const V diameter = !normal_r || !spring_r ? l.ai + l.aj : l.ai;
      fn = hertz_force(p.kn, p.gn, normal_r ? reduced : diameter, dn, -vn);
      if (form.tangential != CoulombTangential::Constant)
        scale = lane_sqrt((spring_r ? reduced : diameter) * delta);
    } else if constexpr (L == BatchLaw::Hysteretic) {
      fn = hysteretic_elastic_force(p.k1, p.kn, p.kc, dn, l.D) + p.gn * -vn;
    } else {
      fn = linear_normal_force(p.kn, p.gn, dn, -vn);
    }
    const V wi[3] = {l.wi0, l.wi1, l.wi2}, wj[3] = {l.wj0, l.wj1, l.wj2};
    V li, lj, vt[3];
    contact_slip(dv, n, vn, delta, l.ai, l.aj, wi, wj, li, lj, vt);
    V s[3] = {l.s0, l.s1, l.s2};
    rotate_into_plane_lanes(s, n, active);
    for (int d = 0; d < 3; ++d) s[d] += vt[d] * vdt;
    V k = p.kt, g = p.gt;  // the constant spring's (CoulombTangential::scale: 1)
    if constexpr (restitution) {
      mindlin_restitution_spring(p.kt, p.gt, scale, mstar, k, g);
    } else if constexpr (L == BatchLaw::Hertz) {
      if (form.tangential != CoulombTangential::Constant) k = p.kt * scale, g = p.gt * scale;
    }
    V t[3];
    // The restitution-damped spring keeps no dashpot share after a slip (coulomb_spring).
    coulomb_spring_lanes(s, vt, k, g, p.mus, p.mud, fn, t, !restitution, active);
    l.s0 = s[0], l.s1 = s[1], l.s2 = s[2];
    l.F0 = fn * n[0] + t[0], l.F1 = fn * n[1] + t[1], l.F2 = fn * n[2] + t[2];
    l.Fn = fn, l.N0 = n[0], l.N1 = n[1], l.N2 = n[2], l.Dl = delta;
    V q[3], qj[3];
    contact_torques(n, t, li, lj, q, qj);
    l.q0 = q[0], l.q1 = q[1], l.q2 = q[2];
    l.p0 = qj[0], l.p1 = qj[1], l.p2 = qj[2];
  }
};

#endif  // GRANULAR_CONTACT_BATCH

}  // namespace granular
