// Least-squares fit of a power law y = A x^n through log y against log x, with the standard
// error of the exponent: the scaling of the P-wave modulus with pressure, M ∝ P^n, per
// mixture (n = 1/3 for a Hertzian skeleton whose contact network does not change).
#pragma once
#include <vector>

namespace granular {

struct PowerLawFit {
  int points = 0;
  double exponent = 0;          // n
  double exponent_stderr = 0;   // s / sqrt(sum (log x - mean)^2); NaN with fewer than 3 points
  double prefactor = 0;         // A
  double rms_log_residual = 0;  // of log y
};

// Points with x <= 0 or y <= 0 (no logarithm; an unjammed state's zero modulus) are left out.
// Fewer than two usable points, or a single abscissa, give NaN exponent and prefactor.
PowerLawFit fit_power_law(const std::vector<double>& x, const std::vector<double>& y);

// The same for an exponential y = A e^(n x) (log y against x; x may be of any sign): the
// decay of localized energy with distance, set against a power law over the same points.
PowerLawFit fit_exponential(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace granular
