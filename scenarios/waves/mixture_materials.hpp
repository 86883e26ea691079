// Materials of the mixture study (docs/model_mixtures_and_waves.md §1, DEM parameter set) and the
// contact model built from them for every pair of species:
//
//   [materials.glass]  shear_modulus = 29000 (or young_modulus)   poisson = 0.3
//                      density = 2540   tangential_stiffness = 1e4   viscosity = 100
//                      tangential_viscosity = 0   friction = 0.5
//   [contact]          pair_rule = "harmonic" | "product_over_sum"   (default harmonic)
//                      tangential_law = "constant" | "mindlin_modulus"  (default constant)
//
// Normal force: Hertz with E* mixing, f = (4/3) E* sqrt(R delta) delta + damping, with
// 1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j and R = a_i a_j/(a_i + a_j), whatever the pair
// rule (docs/model_dem.md §4: "Hertz pairs use E* and R"). Damping: the mixtures chapter writes
// gamma sqrt(d delta) d(delta)/dt with d the pair diameter a_i + a_j; the engine's Hertz law
// scales both terms with sqrt(R delta), and d = 4 R for equal spheres, so the coefficient
// of that law is 2 gamma (exact for equal sizes; within 0.1 % for a +-5 % size spread).
// Tangential: a constant spring k_t (tangential_stiffness) with dashpot gamma_t and Coulomb
// friction mu, the source's DEM parameter set; or, with tangential_law = "mindlin_modulus",
// Mindlin's spring k_t = 8 G* sqrt(R delta) from the materials' elastic constants, with
// 1/G* = (2 - nu_i)/G_i + (2 - nu_j)/G_j and its dashpot gamma_t sqrt(R delta) (no
// tangential_stiffness then: the spring follows the overlap as the Hertz normal force does).
// k_t, gamma, gamma_t and mu of unlike species follow the pair rule: "harmonic" is the
// normalised mean 2pq/(p + q) of the engine's species tables, "product_over_sum" is the
// source's pq/(p + q). A species with itself keeps its own values under both rules (as the
// named materials of the wall scenes do), so a one-species packing does not depend on it.
#pragma once
#include <string>
#include <vector>

#include "core/dem/pair_mixing.hpp"
#include "core/io/scene_file.hpp"
#include "kernels/contact/contact_model.hpp"

namespace granular {

struct MixtureMaterial {
  std::string name;
  double young = 0, poisson = 0, density = 0;
  double kt = 0, viscosity = 0, tangential_viscosity = 0, friction = 0;
  std::string modulus_key;  // which reading of the source's moduli column the scene used
};

using MixtureModel = ContactModel<HertzNormal, CoulombTangential>;

struct MixtureMaterials {
  std::vector<MixtureMaterial> materials;  // species slot = index (sorted by name)
  std::string pair_rule = "harmonic";
  std::string tangential_law = "constant";  // or "mindlin_modulus"

  // Reads every [materials.<name>] table, contact.pair_rule and contact.tangential_law; each
  // material gives exactly one of shear_modulus (the source's column, the default reading) or
  // young_modulus, and tangential_stiffness under the constant law only.
  static MixtureMaterials read(const SceneFile& scene);
  int slot(const SceneFile& scene, const std::string& key, const std::string& name) const;
  // The value of a parameter between species a and b (own values for a == b).
  double pair(int a, int b, double p, double q) const;
  double effective_young(int a, int b) const;
  double effective_shear(int a, int b) const;  // G* of Mindlin's spring
  // The model for every pair; `rule` overrides pair_rule ("" keeps it).
  MixtureModel model(const std::string& rule = "") const;
};

}  // namespace granular
