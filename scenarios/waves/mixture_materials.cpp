// Materials of the mixture study and their pair tables (see mixture_materials.hpp).
#include "scenarios/waves/mixture_materials.hpp"

#include <cmath>

namespace granular {

MixtureMaterials MixtureMaterials::read(const SceneFile& s) {
  MixtureMaterials m;
  const auto names = s.tables("materials");
  s.require(!names.empty(), "materials", "needs at least one [materials.<name>] table");
  s.require(static_cast<int>(names.size()) <= kMaxSpecies, "materials",
            "holds more materials than the " + std::to_string(kMaxSpecies) +
                " species slots of the pair tables");
  // Read only where given, so that the summaries of the constant law (every committed
  // reference) stay as they were.
  if (s.has("contact.tangential_law")) m.tangential_law = s.text("contact.tangential_law");
  s.require(m.tangential_law == "constant" || m.tangential_law == "mindlin_modulus",
            "contact.tangential_law",
            "must be \"constant\" (k_t = tangential_stiffness) or \"mindlin_modulus\" "
            "(k_t = 8 G* sqrt(R delta))");
  const bool constant_kt = m.tangential_law == "constant";
  for (const std::string& name : names) {
    const std::string k = "materials." + name;
    MixtureMaterial mat;
    mat.name = name;
    mat.poisson = s.real(k + ".poisson");
    s.require(mat.poisson > -1 && mat.poisson < 0.5 + 1e-12, k + ".poisson",
              "must lie in (-1, 0.5]");
    const bool shear = s.has(k + ".shear_modulus"), young = s.has(k + ".young_modulus");
    s.require(shear != young, k + ".shear_modulus",
              "or " + k +
                  ".young_modulus: give exactly one (the source's moduli column read "
                  "as a shear modulus, its default reading, or as Young's modulus)");
    if (shear) {
      const double G = s.real(k + ".shear_modulus");
      s.require(G > 0, k + ".shear_modulus", "must be positive");
      mat.young = 2 * G * (1 + mat.poisson);
      mat.modulus_key = "shear_modulus";
    } else {
      mat.young = s.real(k + ".young_modulus");
      s.require(mat.young > 0, k + ".young_modulus", "must be positive");
      mat.modulus_key = "young_modulus";
    }
    mat.density = s.real(k + ".density");
    if (constant_kt) {
      mat.kt = s.real(k + ".tangential_stiffness");
      s.require(mat.kt > 0, k + ".tangential_stiffness", "must be positive");
    } else {
      s.require(!s.has(k + ".tangential_stiffness"), k + ".tangential_stiffness",
                "is not used by contact.tangential_law = \"mindlin_modulus\" (k_t = 8 G* "
                "sqrt(R delta) from the elastic constants): remove it, or take the constant law");
    }
    mat.viscosity = s.real(k + ".viscosity", 0.0);
    mat.tangential_viscosity = s.real(k + ".tangential_viscosity", 0.0);
    mat.friction = s.real(k + ".friction");
    s.require(mat.density > 0, k + ".density", "must be positive");
    s.require(mat.viscosity >= 0, k + ".viscosity", "must not be negative");
    s.require(mat.tangential_viscosity >= 0, k + ".tangential_viscosity", "must not be negative");
    s.require(mat.friction >= 0, k + ".friction", "must not be negative");
    m.materials.push_back(mat);
  }
  m.pair_rule = s.text("contact.pair_rule", "harmonic");
  s.require(m.pair_rule == "harmonic" || m.pair_rule == "product_over_sum", "contact.pair_rule",
            "must be \"harmonic\" (2pq/(p + q)) or \"product_over_sum\" (pq/(p + q))");
  return m;
}

int MixtureMaterials::slot(const SceneFile& s, const std::string& key,
                           const std::string& name) const {
  for (size_t i = 0; i < materials.size(); ++i)
    if (materials[i].name == name) return static_cast<int>(i);
  s.require(false, key, "names no material of [materials] (\"" + name + "\")");
  return -1;
}

double MixtureMaterials::pair(int a, int b, double p, double q) const {
  return a == b ? p : mix_pair(pair_rule_named(pair_rule), p, q);
}

double MixtureMaterials::effective_young(int a, int b) const {
  const MixtureMaterial &i = materials[a], &j = materials[b];
  return 1.0 / ((1 - i.poisson * i.poisson) / i.young + (1 - j.poisson * j.poisson) / j.young);
}

double MixtureMaterials::effective_shear(int a, int b) const {
  const MixtureMaterial &i = materials[a], &j = materials[b];
  const double Gi = i.young / (2 * (1 + i.poisson)), Gj = j.young / (2 * (1 + j.poisson));
  return 1.0 / ((2 - i.poisson) / Gi + (2 - j.poisson) / Gj);
}

MixtureModel MixtureMaterials::model(const std::string& rule) const {
  MixtureMaterials m = *this;
  if (!rule.empty()) m.pair_rule = rule;
  MixtureModel out;
  out.normal.table = PairTable<HertzNormal::Params>::uniform({0, 0, true});
  out.tangential.table = PairTable<CoulombTangential::Params>::uniform({});
  const int n = static_cast<int>(materials.size());
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const MixtureMaterial &i = materials[a], &j = materials[b];
      // 2 gamma: the source's sqrt(d delta) with d = a_i + a_j = 4 R for equal spheres.
      out.normal.table.p[a][b] = {4.0 / 3.0 * m.effective_young(a, b),
                                  2.0 * m.pair(a, b, i.viscosity, j.viscosity), true};
      const double mu = m.pair(a, b, i.friction, j.friction);
      const double gt = m.pair(a, b, i.tangential_viscosity, j.tangential_viscosity);
      out.tangential.table.p[a][b] =
          m.tangential_law == "constant"
              ? CoulombTangential::Params{m.pair(a, b, i.kt, j.kt), gt, mu, mu,
                                          CoulombTangential::Constant}
              : CoulombTangential::Params{8 * m.effective_shear(a, b), gt, mu, mu,
                                          CoulombTangential::MindlinReducedRadius};
    }
  return out;
}

}  // namespace granular
