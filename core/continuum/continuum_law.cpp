// Moduli and volume-fraction update of the hypoelastic continuum law.
#include "core/continuum/continuum_law.hpp"

#include <cmath>

#include "core/run/error.hpp"

namespace granular {

ContinuumConstants ContinuumConstants::spec_example() {
  ContinuumConstants c;
  c.nu0 = 0.665, c.C0 = 4, c.C1 = 9.5, c.alpha = 0.375, c.g3 = 1.24, c.Fv0 = 3.63;
  c.K0 = 16005, c.K1 = 4350, c.G0 = 13700, c.G1 = 5083.5, c.G2 = 0.723653;
  c.units = "as the source prints them, without a unit (docs/model_continuum.md §6)";
  return c;
}

void ContinuumConstants::check() const {
  auto need = [](bool ok, const char* name, const char* what) {
    if (!ok) throw InputError(std::string("continuum law constant ") + name + " " + what);
  };
  const double all[] = {nu0, C0, C1, alpha, g3, Fv0, K0, K1, G0, G1, G2};
  for (double v : all) need(std::isfinite(v), "(one of them)", "is not finite");
  need(nu0 > 0 && nu0 < 1, "nu0", "must lie in (0, 1)");
  need(alpha > 0, "alpha", "must be positive");
  need(G2 > 0, "G2", "must be positive");
  need(g3 > 0, "g3", "must be positive");
}

VolumeFractionUpdate volume_fraction_update_from(const std::string& name) {
  if (name == "mass_conservation") return VolumeFractionUpdate::mass_conservation;
  if (name == "exponential") return VolumeFractionUpdate::exponential;
  throw InputError("volume fraction update '" + name +
                   "' is unknown: use mass_conservation or exponential");
}

const char* to_string(VolumeFractionUpdate u) {
  return u == VolumeFractionUpdate::mass_conservation ? "mass_conservation" : "exponential";
}

double volume_fraction(VolumeFractionUpdate u, double nu_ref, double J) {
  return u == VolumeFractionUpdate::mass_conservation ? nu_ref / J : nu_ref * std::exp(1.0 - J);
}

ContinuumModuli continuum_moduli(const ContinuumConstants& c, double nu) {
  ContinuumModuli m;
  if (!(nu >= c.nu0)) return m;  // also catches a NaN nu: no network, no stiffness
  m.jammed = true;
  const double x = nu / c.nu0 - 1.0;
  m.C = c.C0 + c.C1 * (x > 0 ? std::pow(x, c.alpha) : 0.0);
  m.Fv = m.C * c.g3 * nu;
  const double dF = m.Fv - c.Fv0;
  m.K = c.K0 + c.K1 * dF;
  if (m.K < 0) m.K = 0, m.bulk_floor = true;
  if (dF > 0) {
    m.G = c.G0 + c.G1 * std::pow(dF, c.G2);
  } else {
    m.G = c.G0;
    m.shear_floor = dF < 0;
  }
  if (m.G < 0) m.G = 0;
  return m;
}

}  // namespace granular
