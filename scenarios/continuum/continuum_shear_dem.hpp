// A short DEM pure-shear test for validating the continuum law beyond its probing strains:
// a frictionless linear packing compressed to a target volume fraction and relaxed (as the
// mu = 0 preparation of the moduli studies), then sheared at constant volume (compress x,
// stretch y) with tangential springs and the friction of the shear stage, recording the
// stress along the path.
#pragma once
#include <vector>

#include "scenarios/common/packing.hpp"

namespace granular {

struct DemShearSpec {
  GasSpec gas;
  double kn = 0, gamma_n = 0, kt = 0, gamma_t = 0;
  double mu = 0;  // friction while shearing (the preparation is frictionless)
  double damping_background = 0, damping_rotational = 0;
  double dt = 0, skin = 0, max_overlap = 0.5;
  double phi = 0;                     // volume fraction of the sheared state
  double volumetric_strain_rate = 0;  // compression rate (per us)
  double relax_ratio = 1e-8;          // E_kin / E_pot that ends the relaxation
  long relax_max_steps = 0;
  double strain = 0, strain_rate = 0;  // largest axial true strain and its rate (per us)
  int samples = 0;                     // stress samples along the shear path
};

struct DemShearPath {
  double phi = 0, z_corrected = 0;
  // F = diag(stretch_x, stretch_y, stretch_z) of each sample relative to the sheared state,
  // and the stress (positive in compression, MPa), first entry: before shearing.
  std::vector<double> stretch_x, stretch_y, stretch_z;
  std::vector<double> sxx, syy, szz, sxy, sxz, syz, pressure, z;
};

DemShearPath run_dem_pure_shear(const DemShearSpec& spec);

}  // namespace granular
