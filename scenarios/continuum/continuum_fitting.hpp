// Fitting the continuum law's constants to the engine's own elastic-moduli studies, and
// comparing the fitted law with the DEM pressure along the preparation's isotropic path.
// Host code: reads a study's results.h5 (table and preparation series) and summary.json.
#pragma once
#include <string>
#include <vector>

#include "core/continuum/continuum_law.hpp"
#include "core/continuum/least_squares.hpp"

namespace granular {

// One preparation friction of an elastic_moduli study. Moduli and pressures in MPa (N/mm^2,
// the engine's units): K = K* kn_mean / dbar, the element tests' K* = K dbar / kn_mean.
struct ModuliData {
  std::string study;  // the study directory, as given
  std::string name;   // e.g. "moduli_linear mu=0.5"
  double mu = 0;      // preparation friction
  double d_mean = 0;  // mean diameter dbar of the study (mm)
  // Jammed configurations of the probing table (unloading branch, relaxed).
  std::vector<double> phi, z, fabric, K, G, pressure, kn_mean;
  // Preparation series: isotropic loading up to phi_max (indices < peak), then unloading.
  std::vector<double> prep_phi, prep_pressure, prep_z;
  size_t peak = 0;
};

// Every preparation friction of the study in <dir> (results.h5 and summary.json).
std::vector<ModuliData> read_moduli_study(const std::string& dir, const std::string& label);

struct FittedConstant {
  const char* name;
  double value, std_error;
  const char* unit;
  bool at_bound;
};

struct ContinuumFit {
  ContinuumConstants law;
  std::vector<FittedConstant> constants;
  LeastSquaresFit coordination, fabric, bulk, shear;  // the four fits, residuals inside
  int coordination_points = 0;                        // unloading-series points used
  double z_min = 0;                                   // lowest Z* kept for the C* fit
};

// C*(nu) from the unloading branch of the preparation series (points with Z* >= z_min and
// P > 0), g3 from the table's fabric trace, F_v0 = C0 g3 nu0 (the fabric of the fitted law at
// jamming, so the shear power law is defined from nu0 on), K0, K1 and G0, G1, G2 from the
// probed moduli against the measured fabric trace.
ContinuumFit fit_continuum_law(const ModuliData& d, double z_min);

// The fitted law against the DEM along the preparation's isotropic path: the law is
// compressed from nu0 (stress-free) to the largest phi of the series, then decompressed to
// its smallest, by stretch increments `step`; each branch is compared with the DEM branch,
// and the unloading branch also with the relaxed probing configurations.
struct BranchError {
  std::vector<double> phi, p_dem, p_law;     // at the DEM points the law covers
  double rms = 0, max_abs = 0, p_scale = 0;  // p_scale: largest DEM pressure of the branch
};
struct IsotropicValidation {
  BranchError loading, unloading, configurations;
  std::vector<double> law_phi, law_p;  // the law's whole cycle
};
IsotropicValidation validate_isotropic(const ModuliData& d, const ContinuumConstants& law,
                                       VolumeFractionUpdate update, double step);

}  // namespace granular
