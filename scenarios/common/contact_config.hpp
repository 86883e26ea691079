// Contact physics chosen in a scene file ([contact] table) and turned into the compile-time
// model type: `with_contact_model(config, f)` calls f with a ContactModel<Normal, Tangential,
// Rolling> instance, so each combination runs its own specialised kernels.
#pragma once
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>

#include "core/io/scene_file.hpp"
#include "core/run/error.hpp"
#include "kernels/contact/contact_model.hpp"

namespace granular {

struct ContactConfig {
  std::string normal = "linear";    // linear | hertz | hysteretic
  std::string tangential = "none";  // none | coulomb
  bool rolling = false;
  LinearNormal::Params linear;
  HertzNormal::Params hertz;
  HystereticNormal::Params hysteretic;
  CoulombTangential::Params coulomb;
  RollingTorsion::Params rolling_params;

  // Reads [contact] from a scene; every key is checked, unknown ones are reported later.
  static ContactConfig read(const SceneFile& scene);
};

// The keys of a normal law, read and checked the one way every scene reads them: the moduli
// studies and the Python package through ContactConfig::read, the collision and compression
// drivers directly (docs/contact_laws.md).
// contact.kn and contact.gamma_n (N mm-1, ug us-1); gamma_n defaults to `gamma_default`, or
// must be given where that is empty.
LinearNormal::Params read_linear_normal(const SceneFile& s,
                                        std::optional<double> gamma_default = 0.0);
// contact.k2, contact.k1 (the loading and unloading stiffnesses, N mm-1) and contact.gamma_n
// of the hysteretic law; its adhesive stiffness kc is the caller's (one value in a study, a
// list in a collision sweep).
HystereticNormal::Params read_hysteretic_branches(const SceneFile& s);

template <class F>
void with_contact_model(const ContactConfig& c, F&& f) {
  auto with_normal = [&](auto normal) {
    auto with_tangential = [&](auto tangential) {
      using Normal = std::decay_t<decltype(normal)>;
      using Tangential = decltype(tangential);
      // Rolling resistance without tangential forces is refused by ContactConfig::read, so
      // that combination is never instantiated (each one is a whole set of kernels).
      if constexpr (std::is_same_v<Tangential, NoTangential>) {
        if (c.rolling) throw InputError("contact.rolling needs contact.tangential = \"coulomb\"");
        f(ContactModel<Normal, Tangential, NoRolling>{normal, tangential, {}});
      } else if (c.rolling) {
        f(ContactModel<Normal, Tangential, RollingTorsion>{
            normal, tangential, RollingTorsion::uniform(c.rolling_params)});
      } else {
        f(ContactModel<Normal, Tangential, NoRolling>{normal, tangential, {}});
      }
    };
    if (c.tangential == "coulomb") {
      with_tangential(CoulombTangential{PairTable<CoulombTangential::Params>::uniform(c.coulomb)});
    } else {
      with_tangential(NoTangential{});
    }
  };
  if (c.normal == "linear")
    with_normal(LinearNormal{PairTable<LinearNormal::Params>::uniform(c.linear)});
  else if (c.normal == "hertz")
    with_normal(HertzNormal{PairTable<HertzNormal::Params>::uniform(c.hertz)});
  else
    with_normal(HystereticNormal{PairTable<HystereticNormal::Params>::uniform(c.hysteretic)});
}

}  // namespace granular
