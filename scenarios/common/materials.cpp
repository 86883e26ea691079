// Materials from scene files and their Hertz-Mindlin pair tables (see materials.hpp).
#include "scenarios/common/materials.hpp"

#include <cmath>
#include <limits>

#include "core/dem/pair_mixing.hpp"
#include "core/dem/restitution.hpp"

namespace granular {

MaterialSet MaterialSet::read(const SceneFile& s) {
  MaterialSet m;
  const auto names = s.tables("materials");
  s.require(!names.empty(), "materials", "needs at least one [materials.<name>] table");
  s.require(static_cast<int>(names.size()) <= kMaxSpecies, "materials",
            "holds more materials than the " + std::to_string(kMaxSpecies) +
                " species slots of the pair tables");
  for (const std::string& name : names) {
    m.slot[name] = static_cast<int>(m.materials.size());
    m.materials.push_back(Material::read(s, "materials." + name, name));
  }
  m.read_contact(s);
  return m;
}

Material Material::read(const SceneFile& s, const std::string& k, const std::string& name) {
  Material mat;
  mat.name = name;
  mat.young = s.real_or_infinite(k + ".young_modulus");
  mat.poisson = s.real(k + ".poisson");
  mat.density = s.real(k + ".density", 0.0);
  mat.friction = s.real(k + ".friction", 0.0);
  mat.restitution = s.real(k + ".restitution", 1.0);
  s.require(mat.young > 0, k + ".young_modulus", "must be positive (inf: rigid)");
  s.require(mat.poisson > -1 && mat.poisson < 0.5 + 1e-12, k + ".poisson", "must lie in (-1, 0.5]");
  s.require(mat.density >= 0 && std::isfinite(mat.density), k + ".density",
            "must be a finite, non-negative number");
  s.require(mat.friction >= 0, k + ".friction", "must not be negative (inf: no sliding)");
  s.require(mat.restitution > 0 && mat.restitution <= 1, k + ".restitution", "must lie in (0, 1]");
  return mat;
}

void MaterialSet::read_contact(const SceneFile& s) {
  MaterialSet& m = *this;
  const std::string tangential = s.text("contact.tangential", "mindlin");
  s.require(tangential == "none" || tangential == "mindlin", "contact.tangential",
            "must be \"none\" or \"mindlin\"");
  m.tangential = tangential == "mindlin";
  m.damping = s.text("contact.damping", "restitution_exact");
  s.require(m.damping == "restitution_exact" || m.damping == "restitution_common",
            "contact.damping", "must be \"restitution_exact\" or \"restitution_common\"");
  m.pair_rule = s.text("contact.pair_rule", "harmonic");
  s.require(m.pair_rule == "harmonic" || m.pair_rule == "product_over_sum", "contact.pair_rule",
            "must be \"harmonic\" or \"product_over_sum\"");
  const std::string limit = s.text("contact.coulomb_normal", "total");
  s.require(limit == "total" || limit == "elastic", "contact.coulomb_normal",
            "must be \"total\" (elastic + dashpot) or \"elastic\"");
  m.coulomb_elastic = limit == "elastic";
}

MaterialSet MaterialSet::only(int s) const {
  MaterialSet one = *this;
  one.materials = {materials.at(s)};
  one.slot = {{materials.at(s).name, 0}};
  return one;
}

int MaterialSet::at(const SceneFile& s, const std::string& key) const {
  const std::string name = s.text(key);
  const auto it = slot.find(name);
  s.require(it != slot.end(), key, "names no material of [materials] (\"" + name + "\")");
  return it->second;
}

double MaterialSet::pair(double p, double q) const {
  return mix_pair(pair_rule_named(pair_rule), p, q);
}

double MaterialSet::effective_young(int a, int b) const {
  const Material &i = materials[a], &j = materials[b];
  return granular::effective_young(i.young, i.poisson, j.young, j.poisson);
}

double MaterialSet::effective_shear(int a, int b) const {
  const Material &i = materials[a], &j = materials[b];
  const double Gi = i.young / (2 * (1 + i.poisson)), Gj = j.young / (2 * (1 + j.poisson));
  return granular::effective_shear(Gi, i.poisson, Gj, j.poisson);
}

double MaterialSet::restitution(int a, int b) const {
  if (a == b) return materials[a].restitution;
  return std::min(1.0, pair(materials[a].restitution, materials[b].restitution));
}

double MaterialSet::alpha(int a, int b) const {
  const double e = restitution(a, b);
  return damping == "restitution_common" ? hertz_alpha_common(e) : hertz_alpha_exact(e);
}

HertzRestitutionNormal MaterialSet::normal() const {
  HertzRestitutionNormal h{PairTable<HertzRestitutionNormal::Params>::uniform({0, 0})};
  const int n = static_cast<int>(materials.size());
  for (int a = 0; a < n; ++a)
    for (int b = a; b < n; ++b) {
      // Two rigid materials never touch (walls do not meet walls): leave the entry empty.
      if (materials[a].rigid() && materials[b].rigid()) continue;
      h.table.p[a][b] = h.table.p[b][a] =
          HertzRestitutionNormal::modulus_form(effective_young(a, b), alpha(a, b));
    }
  return h;
}

CoulombTangential MaterialSet::tangential_law() const {
  CoulombTangential t;
  const int n = static_cast<int>(materials.size());
  for (int a = 0; a < kMaxSpecies; ++a)
    for (int b = 0; b < kMaxSpecies; ++b)
      t.table.p[a][b] = {0, 0, 0, 0, CoulombTangential::MindlinRestitution};
  for (int a = 0; a < n; ++a)
    for (int b = a; b < n; ++b) {
      if (materials[a].rigid() && materials[b].rigid()) continue;
      const double mu =
          a == b ? materials[a].friction : pair(materials[a].friction, materials[b].friction);
      t.table.p[a][b] =
          t.table.p[b][a] = {8.0 * effective_shear(a, b), mindlin_gt_common(restitution(a, b)), mu,
                             mu, CoulombTangential::MindlinRestitution};
    }
  return t;
}

}  // namespace granular
