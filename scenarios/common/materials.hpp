// Named materials of a scene ([materials.<name>]) and the Hertz-Mindlin model built from
// them for every pair of materials: particles and walls alike take a species slot.
//
//   [materials.glass]  young_modulus = 63e3   poisson = 0.23   density = 2500
//                      friction = 0.3   restitution = 0.9
//   [materials.steel]  young_modulus = inf    poisson = 0.3   friction = 0.3   restitution = 0.9
//                      (inf: a rigid material, whose term drops from 1/E* and 1/G* exactly)
//   [contact]          tangential = "none" | "mindlin"       (default "mindlin")
//                      damping = "restitution_exact" | "restitution_common"  (default exact)
//                      pair_rule = "harmonic" | "product_over_sum"           (default harmonic)
//                      coulomb_normal = "total" | "elastic"  the normal force of the Coulomb
//                      limit (default total: elastic + dashpot; docs/contact_laws.md)
//
// Pairs: 1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j, 1/G* = (2 - nu_i)/G_i + (2 - nu_j)/G_j
// with G = E/(2(1 + nu)); restitution and friction of unlike materials by the pair rule
// (harmonic 2pq/(p + q) keeps like pairs at their own values; product over sum pq/(p + q)
// halves them, as the source writes it).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "core/io/scene_file.hpp"
#include "kernels/contact/contact_model.hpp"

namespace granular {

struct Material {
  std::string name;
  double young = 0, poisson = 0, density = 0, friction = 0, restitution = 1;
  bool rigid() const { return young == std::numeric_limits<double>::infinity(); }
  // The keys <key>.young_modulus, .poisson, .density, .friction, .restitution, checked.
  static Material read(const SceneFile& scene, const std::string& key, const std::string& name);
};

struct MaterialSet {
  std::vector<Material> materials;  // slot = index (sorted by name)
  std::map<std::string, int> slot;
  bool tangential = true;
  std::string damping = "restitution_exact";
  std::string pair_rule = "harmonic";
  bool coulomb_elastic = false;  // Coulomb limit on the elastic normal force (ContactModel)

  static MaterialSet read(const SceneFile& scene);
  // The [contact] options (tangential, damping, pair_rule) of the scene.
  void read_contact(const SceneFile& scene);
  int at(const SceneFile& scene, const std::string& key) const;  // slot of the named material
  // The set with one material only (in slot 0), same contact options: a run that uses one
  // material gets its own time-step guard, not the stiffest and lightest of all pairs.
  MaterialSet only(int slot) const;
  double pair(double p, double q) const;  // restitution/friction of a pair by the pair rule
  double effective_young(int a, int b) const;
  double effective_shear(int a, int b) const;
  double restitution(int a, int b) const;
  double alpha(int a, int b) const;  // damping coefficient of the chosen mapping
  HertzRestitutionNormal normal() const;
  CoulombTangential tangential_law() const;
};

// Calls f with the model of the material set: ContactModel<HertzRestitutionNormal> without
// friction, or with the Mindlin tangential law.
template <class F>
void with_material_model(const MaterialSet& m, F&& f) {
  if (m.tangential) {
    ContactModel<HertzRestitutionNormal, CoulombTangential> model{
        m.normal(), m.tangential_law(), {}};
    model.coulomb_elastic_normal = m.coulomb_elastic;
    f(model);
  } else
    f(ContactModel<HertzRestitutionNormal>{m.normal(), {}, {}});
}

}  // namespace granular
