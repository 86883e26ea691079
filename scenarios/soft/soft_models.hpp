// The force models of the soft-particle scenes: classical Hertz, MC-strain with a list of
// prefactors gamma and MC-stress with a list of prefactors beta
// (docs/model_multicontact.md §2-4), read from
//   [multicontact]  classical = true   strain_gamma = [1.0, 1.12]   stress_beta = [1.0, 1.65]
//                   own_contact = false   mean = false   walls = true   stress_area = "hertz"
// (an empty list runs no model of its kind; at least one model must remain)
// The three options are the choices the source leaves open; their values go to summary.json
// with the other parameters.
#pragma once
#include <sstream>
#include <string>
#include <vector>

#include "core/io/scene_file.hpp"
#include "kernels/dem/multicontact.hpp"
#include "scenarios/common/materials.hpp"

namespace granular {

// The multi-contact factors the scenes accept: the source uses 1 to 1.65. Far above, the
// corrections outweigh the pair law, whose stiffness is all the time-step guard sees (with
// strain_gamma = 1e308 the forces became NaN without a stop).
constexpr double kMaxMultiContactFactor = 10.0;

struct SoftModel {
  std::string label;  // "classical", "mc_strain_gamma_1.12", "mc_stress_beta_1.65"
  MultiContact mc;
};

// The law's elastic constants per species slot, from the materials in those slots.
inline MultiContact with_materials(MultiContact mc, const MaterialSet& m) {
  for (int k = 0; k < kMaxSpecies; ++k) mc.young[k] = 0, mc.poisson[k] = 0;
  for (size_t k = 0; k < m.materials.size(); ++k)
    mc.young[k] = m.materials[k].young, mc.poisson[k] = m.materials[k].poisson;
  return mc;
}

inline std::vector<SoftModel> read_soft_models(const SceneFile& s, const MaterialSet& m) {
  MultiContact base;
  base.own_contact = s.flag("multicontact.own_contact", false);
  base.mean = s.flag("multicontact.mean", false);
  base.walls = s.flag("multicontact.walls", true);
  const std::string area = s.text("multicontact.stress_area", "hertz");
  s.require(area == "hertz" || area == "particle", "multicontact.stress_area",
            "must be \"hertz\" (pi R* delta) or \"particle\" (pi R*^2)");
  base.area = area == "particle" ? MultiContact::ParticleArea : MultiContact::HertzArea;
  base = with_materials(base, m);
  std::vector<SoftModel> out;
  auto label = [](const char* what, double v) {
    std::ostringstream o;
    o << what << v;
    return o.str();
  };
  if (s.flag("multicontact.classical", true)) out.push_back({"classical", base});
  // An empty list runs no model of that kind (classical = true with both lists empty: the
  // classical model alone).
  const std::vector<double> gammas = s.reals_or_none("multicontact.strain_gamma", {1.0});
  const std::vector<double> betas = s.reals_or_none("multicontact.stress_beta", {1.0});
  s.require_distinct("multicontact.strain_gamma", gammas);
  s.require_distinct("multicontact.stress_beta", betas);
  for (double g : gammas) {
    s.require(g > 0 && g <= kMaxMultiContactFactor, "multicontact.strain_gamma",
              "must lie in (0, 10]");
    SoftModel sm{label("mc_strain_gamma_", g), base};
    sm.mc.mode = MultiContact::Strain, sm.mc.gamma = g;
    out.push_back(sm);
  }
  for (double b : betas) {
    s.require(b > 0 && b <= kMaxMultiContactFactor, "multicontact.stress_beta",
              "must lie in (0, 10]");
    SoftModel sm{label("mc_stress_beta_", b), base};
    sm.mc.mode = MultiContact::Stress, sm.mc.beta = b;
    out.push_back(sm);
  }
  s.require(!out.empty(), "multicontact.classical",
            "is false and strain_gamma and stress_beta are empty: no model to run");
  return out;
}

}  // namespace granular
