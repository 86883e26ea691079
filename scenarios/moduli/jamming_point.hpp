// The jamming density of a prepared packing, read from its decompression series: near
// jamming the pressure vanishes as P ∝ (phi - phi_J)^alpha (alpha = 1 for linear contacts,
// 3/2 for Hertz), so P^(1/alpha) is a straight line in phi whose root is phi_J. The fit uses
// the unloading samples with 0 < P <= p_max (P* for laws with a constant stiffness). The
// lowest density of the branch that still has a contact network and the highest that has
// none bracket it without a fit where the unloading is slow; at fast rates the network
// flickers near jamming and the two overlap, giving the width of that range instead.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace granular {

struct JammingPoint {
  int variant = 0;
  int points = 0;                   // samples in the fit
  double phi_j = 0;                 // root of the fitted line (NaN: fewer than 4 points)
  double phi_j_stderr = 0;          // from the fit's parameter covariance
  double phi_lowest_jammed = 0;     // smallest phi of the branch with Z > 0 (NaN if none)
  double phi_highest_unjammed = 0;  // largest phi of the branch with Z = 0 (NaN if none)
};

// `prep`: the preparation series (phi, z_corrected, direction, variant and `pressure_key`).
std::vector<JammingPoint> jamming_points(const std::map<std::string, std::vector<double>>& prep,
                                         const std::string& pressure_key, double alpha,
                                         double p_max);

}  // namespace granular
