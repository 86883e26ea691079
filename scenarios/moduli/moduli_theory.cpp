// EMT and fluctuation theory formulas (see moduli_theory.hpp).
#include "scenarios/moduli/moduli_theory.hpp"

#include <cmath>
#include <initializer_list>

namespace granular {

TheoryResult moduli_theory(const TheoryInput& in) {
  TheoryResult r;
  const double Z = in.z, phi = in.phi;
  r.chi = in.chi >= 0 ? in.chi : 1.0 / (phi * Z);
  const double base = phi * Z * in.D;  // phi Z D
  r.K_emt = base / (3 * M_PI);
  r.G_emt = (1 + 1.5 * in.kt_kn) * base / (5 * M_PI);
  r.rho = (22 - 3 * Z) / 24 * (1 / Z - 1 / (Z * Z)) + r.chi / 8;
  r.zeta = -(66 - 9 * Z) / (26 * Z) * (1 - 24 / (13 * Z)) - 261.0 / 676.0 * r.chi;
  const double ring = 1 - 2 * r.rho + 2 * r.zeta;
  r.rho_s = r.rho * ring;
  r.zeta_s = r.zeta * ring;
  auto K = [&](double rho, double rho_s) { return (1 - 2 * (rho + rho_s)) * base / (3 * M_PI); };
  auto G = [&](double rho, double rho_s, double zeta, double zeta_s) {
    return (1 - 2 * (rho + rho_s)) * base / (5 * M_PI) +
           1.5 * in.kt_kn * (1 - 2 * (rho + rho_s) + 2 * (zeta + zeta_s)) * base / (5 * M_PI);
  };
  r.K_ft1 = K(r.rho, 0), r.G_ft1 = G(r.rho, 0, r.zeta, 0);
  r.K_ft2 = K(r.rho, r.rho_s), r.G_ft2 = G(r.rho, r.rho_s, r.zeta, r.zeta_s);
  // With (nearly) no contacts the closures divide by zero: the theories say nothing there
  // (NaN, "not applicable"), never inf.
  for (double* v : {&r.chi, &r.rho, &r.zeta, &r.rho_s, &r.zeta_s, &r.K_emt, &r.G_emt, &r.K_ft1,
                    &r.G_ft1, &r.K_ft2, &r.G_ft2})
    if (std::isinf(*v)) *v = std::nan("");
  return r;
}

}  // namespace granular
