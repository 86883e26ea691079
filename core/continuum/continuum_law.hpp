// The micro-informed hypoelastic law of docs/model_continuum.md: bulk and shear moduli as
// functions of the solid volume fraction nu through the coordination number C*(nu) and the
// fabric trace F_v, and the volume-fraction update from J = det F. Host code, no Kokkos.
#pragma once
#include <string>

namespace granular {

struct ContinuumConstants {
  double nu0 = 0;                     // jamming volume fraction: C* = 0 below it
  double C0 = 0, C1 = 0, alpha = 1;   // C*(nu) = C0 + C1 (nu/nu0 - 1)^alpha
  double g3 = 0;                      // F_v = C* g3 nu
  double Fv0 = 0;                     // reference fabric trace of K and G
  double K0 = 0, K1 = 0;              // K = K0 + K1 (F_v - F_v0)
  double G0 = 0, G1 = 0, G2 = 1;      // G = G0 + G1 (F_v - F_v0)^G2
  std::string units = "unspecified";  // unit system of K0, K1, G0, G1 (and of the stress)

  // The spec's example constants (docs/model_continuum.md §2), for the regression of its
  // isotropic path.
  static ContinuumConstants spec_example();
  // Throws InputError naming the first constant that makes the law meaningless.
  void check() const;
};

// How nu follows the volume change J relative to a state of volume fraction nu_ref.
enum class VolumeFractionUpdate {
  mass_conservation,  // nu = nu_ref / J (exact)
  exponential,        // nu = nu_ref exp(-(J - 1)), the spec's first-order form
};
VolumeFractionUpdate volume_fraction_update_from(const std::string& name);  // throws InputError
const char* to_string(VolumeFractionUpdate u);
double volume_fraction(VolumeFractionUpdate u, double nu_ref, double J);

// Moduli at one volume fraction, with the branch of the law that produced them.
struct ContinuumModuli {
  double C = 0, Fv = 0, K = 0, G = 0;
  bool jammed = false;       // nu >= nu0
  bool shear_floor = false;  // jammed but F_v < F_v0: the power law has no real value there
  bool bulk_floor = false;   // K0 + K1 (F_v - F_v0) < 0, clipped to 0
};

// The rules where the source leaves the law undefined (README "Continuum law"):
//  - nu < nu0: an unjammed packing has no contact network, so C* = F_v = 0 and K = G = 0;
//  - F_v < F_v0 while jammed: (F_v - F_v0)^G2 has no real value, the term is taken as 0
//    (G = G0), which is the limit of the power law at F_v0 and keeps G continuous;
//  - a negative K from the linear law is clipped to 0 (a stable material cannot have K < 0).
// None of them produces a NaN for any finite nu.
ContinuumModuli continuum_moduli(const ContinuumConstants& c, double nu);

}  // namespace granular
