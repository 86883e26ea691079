// Strain-rate modes of the periodic box (docs/model_dem.md §5), as diagonal rate tensors for
// apply_affine_strain: isotropic, volume-conserving pure shear, uniaxial, general diagonal.
// Strains are reported as true (logarithmic) strains ln(L / L_ref) per axis.
#pragma once
#include <array>
#include <cmath>
#include <string>

#include "core/dem/box.hpp"
#include "core/run/error.hpp"

namespace granular {

// rate > 0 stretches; the isotropic mode compresses with a negative rate. `rate` is the
// volumetric rate for the isotropic mode and the axial rate otherwise.
inline std::array<double, 3> strain_rates(const std::string& mode, double rate,
                                          const std::array<double, 3>& diagonal = {0, 0, 0}) {
  if (mode == "isotropic") return {rate / 3, rate / 3, rate / 3};
  if (mode == "pure_shear") return {rate, -rate, 0.0};
  if (mode == "uniaxial") return {rate, 0.0, 0.0};
  if (mode == "diagonal") return diagonal;
  throw InputError("unknown strain mode '" + mode +
                   "' (isotropic, pure_shear, uniaxial, diagonal)");
}

inline std::array<double, 3> true_strain(const PeriodicBox& box, const PeriodicBox& reference) {
  return {std::log(box.len[0] / reference.len[0]), std::log(box.len[1] / reference.len[1]),
          std::log(box.len[2] / reference.len[2])};
}

}  // namespace granular
