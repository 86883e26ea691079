// Pair parameter tables from per-species parameters. Unless a pair is given explicitly,
// each parameter of a pair of different species is the normalised harmonic mean
// 2 p_i p_j / (p_i + p_j) ("product over sum", scaled so that a species paired with itself
// keeps its own values). Hertz pairs of different materials combine moduli instead:
// 1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j (HertzNormal::modulus_form). For the laws built on
// E* and G* (HertzRestitutionNormal, CoulombTangential::MindlinRestitution) the harmonic mean
// of the like-pair coefficients K = (4/3) E*_ii, kt = 8 G*_ii is that combination itself,
// and it is taken in the series form 2/(1/p_i + 1/p_j), which keeps a rigid species
// (E = G = infinity) exact.
#pragma once
#include <optional>
#include <stdexcept>
#include <vector>

#include "core/dem/pair_mixing.hpp"
#include "kernels/contact/contact_model.hpp"

namespace granular {

inline double harmonic_mix(double a, double b) { return mix_pair(PairRule::Harmonic, a, b); }

// Series form of the same mean: exact with an infinite member (2/(1/inf + 1/b) = 2b).
inline double series_mix(double a, double b) {
  if (a == b) return a;
  return 2.0 / (1.0 / a + 1.0 / b);
}

inline LinearNormal::Params mix(const LinearNormal::Params& a, const LinearNormal::Params& b) {
  return {harmonic_mix(a.kn, b.kn), harmonic_mix(a.gn, b.gn)};
}
inline HystereticNormal::Params mix(const HystereticNormal::Params& a,
                                    const HystereticNormal::Params& b) {
  return {harmonic_mix(a.k1, b.k1), harmonic_mix(a.k2, b.k2), harmonic_mix(a.kc, b.kc),
          harmonic_mix(a.gn, b.gn)};
}
// K: E* of the two materials; alpha: harmonic like every damping coefficient (a pair with a
// measured restitution of its own is an explicit override, alpha = hertz_alpha_exact(e_ij)).
inline HertzRestitutionNormal::Params mix(const HertzRestitutionNormal::Params& a,
                                          const HertzRestitutionNormal::Params& b) {
  return {series_mix(a.K, b.K), harmonic_mix(a.alpha, b.alpha)};
}
inline CoulombTangential::Params mix(const CoulombTangential::Params& a,
                                     const CoulombTangential::Params& b) {
  if (a.law != b.law) throw std::invalid_argument("species pair mixes different tangential laws");
  const double kt = a.law == CoulombTangential::MindlinRestitution ? series_mix(a.kt, b.kt)
                                                                   : harmonic_mix(a.kt, b.kt);
  return {kt, harmonic_mix(a.gt, b.gt), harmonic_mix(a.mu_s, b.mu_s), harmonic_mix(a.mu_d, b.mu_d),
          a.law};
}

// overrides[a][b] (if set) replaces the mixed value of the pair (a, b) and (b, a).
template <class P>
PairTable<P> pair_table(const std::vector<P>& species,
                        const std::vector<std::vector<std::optional<P>>>& overrides = {}) {
  const int n = static_cast<int>(species.size());
  if (n < 1 || n > kMaxSpecies) throw std::invalid_argument("between 1 and kMaxSpecies species");
  PairTable<P> t = PairTable<P>::uniform(species[0]);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) t.p[a][b] = a == b ? species[a] : mix(species[a], species[b]);
  for (int a = 0; a < static_cast<int>(overrides.size()) && a < n; ++a)
    for (int b = 0; b < static_cast<int>(overrides[a].size()) && b < n; ++b)
      if (overrides[a][b]) t.p[a][b] = t.p[b][a] = *overrides[a][b];
  return t;
}

}  // namespace granular
