// What a contact model sees of one pair (geometry, relative motion, species) and the
// species-pair parameter table every model carries. Vector helpers are written so that
// swapping i and j negates results exactly: a pair seen from either side (measurements
// walk both entries of the full list) gives exactly opposite vectors.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>

#include "kernels/contact/lane_math.hpp"

namespace granular {

constexpr int kMaxSpecies = 4;

// Parameters per ordered species pair; symmetric by construction on the host.
template <class P>
struct PairTable {
  P p[kMaxSpecies][kMaxSpecies];
  KOKKOS_INLINE_FUNCTION const P& operator()(int si, int sj) const { return p[si][sj]; }
  static PairTable uniform(const P& v) {
    PairTable t;
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b) t.p[a][b] = v;
    return t;
  }
};

// Which species pairs the time-step guard considers: those that can touch in the scene
// (a species with a single particle cannot touch itself; a wall touches only particles).
struct PairMask {
  bool on[kMaxSpecies][kMaxSpecies];
  static PairMask all() { return filled(true); }
  static PairMask none() { return filled(false); }
  static PairMask only(int a, int b) {
    PairMask m = none();
    m.on[a][b] = m.on[b][a] = true;
    return m;
  }
  bool operator()(int a, int b) const { return on[a][b]; }

 private:
  static PairMask filled(bool v) {
    PairMask m;
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = 0; b < kMaxSpecies; ++b) m.on[a][b] = v;
    return m;
  }
};

// The largest of f(parameters) over the pairs of a mask (0 when none): the time-step guard's
// stiffest contact and fastest dashpot, for every law from the same loop.
template <class P, class F>
double max_over(const PairTable<P>& table, const PairMask& pairs, F&& f) {
  double r = 0;
  for (int a = 0; a < kMaxSpecies; ++a)
    for (int b = 0; b < kMaxSpecies; ++b)
      if (pairs(a, b)) r = std::max(r, static_cast<double>(f(table.p[a][b])));
  return r;
}

struct PairState {
  double n[3];       // unit normal, from j towards i
  double delta;      // overlap (> 0 in contact)
  double delta_dot;  // rate of overlap (approach speed)
  double vt[3];      // tangential velocity of i's contact point relative to j's
  double wrel[3];    // omega_i - omega_j
  double ai, aj;     // radii (aj unused for a wall)
  double mstar;      // reduced mass m_i m_j/(m_i + m_j); m_i for a wall (infinite mass)
  int si, sj;        // species (sj: the wall's material slot for a wall)
  bool wall;         // partner is a planar wall: infinite radius and mass
};

KOKKOS_INLINE_FUNCTION double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
KOKKOS_INLINE_FUNCTION void cross3(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
KOKKOS_INLINE_FUNCTION double norm3(const double a[3]) {
  return Kokkos::Experimental::sqrt(dot3(a, a));
}

// A spring vector kept in the tangent plane as the contact rotates: project out the normal
// component and restore the length, so rotation alone stores no energy.
// The spring was in last step's plane, so the normal part x = (s.n)^2/|s|^2 is tiny and the
// restoring factor 1/sqrt(1 - x) is its Taylor series (exact to round-off for x < 1e-4):
// no square root in the common case.
// A spring that lies along the normal (x within kSpringAlongNormal of 1, i.e. within about
// 1e-3 rad of n) has no direction left in the plane: its in-plane part is round-off (a head-on
// impact builds such a spring from the round-off of v_t, n = r/|r| being unit only to
// round-off), and restoring its length would divide by sqrt(1 - x) ~ 0, or take the root of
// a negative number where |n| > 1 makes x > 1. Such a spring is released (set to zero).
constexpr double kSpringAlongNormal = 1e-6;

// The law parts shared with the host's four-lane paths (kernels/contact/lane_law.inc), for
// double.
#define LANE_T double
#define LANE_M bool
#define LANE_FN KOKKOS_FORCEINLINE_FUNCTION
#include "kernels/contact/lane_law.inc"
#undef LANE_T
#undef LANE_M
#undef LANE_FN

// Reduced radius R* = a_i a_j/(a_i + a_j); a wall has infinite radius, so R* = a_i exactly.
// In the pair kernels `wall` is a constant false, so the branch folds away.
KOKKOS_INLINE_FUNCTION double reduced_radius(const PairState& s) {
  return s.wall ? s.ai : reduced_pair(s.ai, s.aj);
}
// The pair length d = a_i + a_j of the "stiffness" Hertz/Mindlin forms. It equals 4 R* for
// equal spheres; a wall contact takes 4 R* = 4 a_i, which keeps the ratio between the
// stiffness and modulus forms of a wall contact the same as for a pair of equal spheres.
KOKKOS_INLINE_FUNCTION double pair_diameter(const PairState& s) {
  return s.wall ? 4.0 * s.ai : s.ai + s.aj;
}

KOKKOS_INLINE_FUNCTION void rotate_into_plane(double s[3], const double n[3]) {
  rotate_into_plane_lanes(s, n, true);
}

// Spring-dashpot with a Coulomb limit, shared by sliding, rolling and torsion:
// trial f = -k s - g v; if |f| > mu_s * fn the contact slips, f becomes mu_d * fn along
// the trial direction and the spring is shortened to match it. Returns the force in f.
// mu_s = infinity never slips. The limit uses |fn| as the spec writes it (the normal force
// includes its dashpot, which is briefly tensile at the end of a damped collision).
//
// The spring after a slip (docs/contact_laws.md, "Slip reset"). With keep_dashpot the spring
// also holds the dashpot's share, s = -(f + g v)/k (Luding's reset, as LAMMPS and MercuryDPM
// write it), so that the trial force of the same step is exactly f. That is consistent only
// while the next step evaluates the law with the same ratio g/k: the next trial force is then
// (k'/k)(f + g (v - v')) - k' v' dt, which opposes the slip (constant laws; the L-delta
// Mindlin laws, whose k and g both scale with sqrt(L delta)). Where g/k changes with the
// overlap (the restitution-damped Mindlin law, g ~ sqrt(k)), the stored share (k'/k) g v
// outgrows the new dashpot g' v, and while the dashpot alone exceeds the Coulomb force the
// friction pushes along the slip. Without keep_dashpot the spring holds the elastic force
// only, s = -f/k: the next trial force (k'/k) f - k' v dt - g' v then opposes the slip.
KOKKOS_INLINE_FUNCTION bool coulomb_spring(double s[3], const double v[3], double k, double g,
                                           double mu_s, double mu_d, double fn, double f[3],
                                           bool keep_dashpot = true) {
  return coulomb_spring_lanes(s, v, k, g, mu_s, mu_d, fn, f, keep_dashpot, true);
}

}  // namespace granular
