// The one rule that gives a pair of unlike species a parameter from the two species' own
// values (docs/model_dem.md, species pairs). Every table of pair parameters goes through it:
// the kernels' pair tables, the materials of the DEM scenes and of the mixture study.
//   harmonic:         p_ij = 2 p_i p_j / (p_i + p_j)  (a species with itself keeps p exactly)
//   product_over_sum: p_ij = p_i p_j / (p_i + p_j)
// An infinite member (a rigid wall, friction that never slides) leaves the finite one's
// limit: harmonic(inf, q) = 2q, product_over_sum(inf, q) = q; both infinite give infinity.
#pragma once
#include <cmath>
#include <string>

namespace granular {

enum class PairRule { Harmonic, ProductOverSum };

inline double mix_pair(PairRule rule, double p, double q) {
  const bool harmonic = rule == PairRule::Harmonic;
  if (p == q && harmonic) return p;  // 2pp/(p + p) can miss p by an ulp; inf stays inf
  if (std::isinf(p) && std::isinf(q)) return p;
  const double f = harmonic ? 2.0 : 1.0;
  if (std::isinf(p)) return f * q;
  if (std::isinf(q)) return f * p;
  return p + q > 0 ? f * p * q / (p + q) : 0.0;
}

// The rule named in a scene ("harmonic" or "product_over_sum"; checked when read).
inline PairRule pair_rule_named(const std::string& name) {
  return name == "product_over_sum" ? PairRule::ProductOverSum : PairRule::Harmonic;
}

}  // namespace granular
