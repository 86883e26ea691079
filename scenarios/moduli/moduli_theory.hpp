// Effective medium theory (affine) and fluctuation theory (pair fluctuations, first and
// second ring) for the bulk and shear moduli of isotropic polydisperse sphere packings,
// docs/model_dem.md §9. Moduli are dimensionless: K* = K dbar / k_n, G* = G dbar / k_n.
#pragma once

namespace granular {

struct TheoryInput {
  double phi = 0;    // volume fraction
  double z = 0;      // corrected coordination number Z (non-rattlers)
  double chi = -1;   // contact-number fluctuation; < 0: use the closure chi = 1/(phi Z)
  double kt_kn = 0;  // tangential over normal stiffness
  // Size moment dbar <d^2>/<d^3>: 26/30 for d uniform in [1, 3] (w = 3). The source quotes
  // 1.15 for that set, its reciprocal <d^3>/(dbar <d^2>) (docs/model_dem.md §7); the studies
  // compute D from each configuration.
  double D = 26.0 / 30.0;
};

struct TheoryResult {
  double chi = 0;                // the value used
  double rho = 0, zeta = 0;      // first-ring corrections
  double rho_s = 0, zeta_s = 0;  // second-ring corrections rho*, zeta*
  double K_emt = 0, G_emt = 0;
  double K_ft1 = 0, G_ft1 = 0;  // fluctuation theory, first ring (rho*, zeta* dropped)
  double K_ft2 = 0, G_ft2 = 0;  // fluctuation theory, second ring
};

TheoryResult moduli_theory(const TheoryInput& in);

}  // namespace granular
