// Reading the [contact] table of a scene (see contact_config.hpp).
#include "scenarios/common/contact_config.hpp"

namespace granular {

namespace {
double friction(const SceneFile& s, const std::string& key, double def) {
  // TOML spells infinity `inf`: mu = inf means no sliding.
  const double mu = s.real(key, def);
  s.require(mu >= 0, key, "must not be negative (use inf for no sliding)");
  return mu;
}
}  // namespace

LinearNormal::Params read_linear_normal(const SceneFile& s, std::optional<double> gamma_default) {
  LinearNormal::Params p;
  p.kn = s.real("contact.kn");
  p.gn = gamma_default ? s.real("contact.gamma_n", *gamma_default) : s.real("contact.gamma_n");
  s.require(p.kn > 0, "contact.kn", "must be positive");
  s.require(p.gn >= 0, "contact.gamma_n", "must not be negative");
  return p;
}

HystereticNormal::Params read_hysteretic_branches(const SceneFile& s) {
  HystereticNormal::Params p;
  p.k2 = s.real("contact.k2");
  p.k1 = s.real("contact.k1");
  p.gn = s.real("contact.gamma_n", 0.0);
  s.require(p.k2 > 0, "contact.k2", "must be positive");
  s.require(p.k1 > 0 && p.k1 <= p.k2, "contact.k1", "must satisfy 0 < k1 <= k2");
  s.require(p.gn >= 0, "contact.gamma_n", "must not be negative");
  return p;
}

ContactConfig ContactConfig::read(const SceneFile& s) {
  ContactConfig c;
  c.normal = s.text("contact.normal", "linear");
  s.require(c.normal == "linear" || c.normal == "hertz" || c.normal == "hysteretic",
            "contact.normal", "must be \"linear\", \"hertz\" or \"hysteretic\"");
  c.tangential = s.text("contact.tangential", "none");
  s.require(c.tangential == "none" || c.tangential == "coulomb", "contact.tangential",
            "must be \"none\" or \"coulomb\"");
  c.rolling = s.flag("contact.rolling", false);
  s.require(
      !(c.rolling && c.tangential == "none"), "contact.rolling",
      "needs contact.tangential = \"coulomb\" (rolling resistance acts on rotating particles)");

  if (c.normal == "linear") {
    c.linear = read_linear_normal(s);
  } else if (c.normal == "hertz") {
    const std::string form = s.text("contact.hertz_form", "stiffness");
    if (form == "stiffness") {
      c.hertz =
          HertzNormal::stiffness_form(s.real("contact.shear_modulus"), s.real("contact.poisson"),
                                      s.real("contact.alpha_n", 0.0));
    } else if (form == "modulus") {
      const double E = s.real("contact.young_modulus"), nu = s.real("contact.poisson");
      c.hertz = HertzNormal::modulus_form(E, nu, E, nu, s.real("contact.gamma", 0.0));
    } else {
      s.require(false, "contact.hertz_form", "must be \"stiffness\" or \"modulus\"");
    }
    s.require(c.hertz.K > 0, "contact.hertz_form",
              "parameters give a non-positive Hertz coefficient");
  } else {
    c.hysteretic = read_hysteretic_branches(s);
    c.hysteretic.kc = s.real("contact.kc", 0.0);
    s.require(c.hysteretic.kc >= 0, "contact.kc", "must not be negative");
  }

  if (c.tangential == "coulomb") {
    const std::string law = s.text("contact.tangential_law", "constant");
    if (law == "constant") {
      c.coulomb.law = CoulombTangential::Constant;
      c.coulomb.kt = s.real("contact.kt");
      c.coulomb.gt = s.real("contact.gamma_t", 0.0);
    } else if (law == "mindlin_stiffness") {
      // k_t = (2 G_p / (2 - nu)) sqrt(dbar delta), gamma_t = alpha_t sqrt(dbar delta)
      c.coulomb.law = CoulombTangential::MindlinPairDiameter;
      c.coulomb.kt = 2 * s.real("contact.shear_modulus") / (2 - s.real("contact.poisson"));
      c.coulomb.gt = s.real("contact.alpha_t", 0.0);
    } else if (law == "mindlin_modulus") {
      // f_t = 8 G* sqrt(R delta) xi, 1/G* = 2 (2 - nu)/G for one material
      const double G = s.real("contact.shear_modulus"), nu = s.real("contact.poisson");
      c.coulomb.law = CoulombTangential::MindlinReducedRadius;
      c.coulomb.kt = 8 * G / (2 * (2 - nu));
      c.coulomb.gt = s.real("contact.gamma_t", 0.0);
    } else {
      s.require(false, "contact.tangential_law",
                "must be \"constant\", \"mindlin_stiffness\" or \"mindlin_modulus\"");
    }
    const double mu = friction(s, "contact.mu", 0.5);
    c.coulomb.mu_s = friction(s, "contact.mu_static", mu);
    c.coulomb.mu_d = friction(s, "contact.mu_dynamic", mu);
    s.require(c.coulomb.mu_d <= c.coulomb.mu_s, "contact.mu_dynamic",
              "must not exceed contact.mu_static");
  }
  if (c.rolling) {
    auto& r = c.rolling_params;
    r.kr = s.real("contact.kr"), r.gr = s.real("contact.gamma_r", 0.0),
    r.mur = friction(s, "contact.mu_r", 0.1);
    r.ko = s.real("contact.ko"), r.go = s.real("contact.gamma_o", 0.0),
    r.muo = friction(s, "contact.mu_o", 0.1);
  }
  return c;
}

}  // namespace granular
