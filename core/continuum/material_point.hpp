// One material point of the hypoelastic continuum law: Kirchhoff stress tau, deformation
// gradient F and volume fraction nu, advanced by the spec's objective convected update
//   f = F_{n+1} F_n^-1,  b = f f^T,  e = (1 - b^-1)/2,  tau_{n+1} = f tau_n f^T + a(nu) : e
// with a(nu) the isotropic elasticity tensor of K(nu), G(nu). Stresses are positive in
// tension (continuum convention); pressure() is the Cauchy pressure -tr(sigma)/3, positive
// in compression like the DEM pressure.
#pragma once
#include <Eigen/Dense>

#include "core/continuum/continuum_law.hpp"

namespace granular {

using Mat3 = Eigen::Matrix3d;

class MaterialPoint {
 public:
  // A point of volume fraction nu_start carrying Kirchhoff stress tau_start (F = 1).
  MaterialPoint(const ContinuumConstants& law, double nu_start,
                VolumeFractionUpdate update = VolumeFractionUpdate::mass_conservation,
                const Mat3& tau_start = Mat3::Zero());

  // Advances to the total deformation gradient F_next (det > 0, else InputError).
  void step_to(const Mat3& F_next);
  // Applies a relative deformation gradient f: F_next = f F.
  void step_by(const Mat3& f) { step_to(f * F_); }

  const Mat3& kirchhoff() const { return tau_; }
  Mat3 cauchy() const { return tau_ / J(); }
  double pressure() const { return -cauchy().trace() / 3.0; }
  // von Mises equivalent of the Cauchy stress, sqrt(3/2 s:s) with s its deviator.
  double deviatoric() const;
  double J() const { return F_.determinant(); }
  double nu() const { return nu_; }
  const Mat3& F() const { return F_; }
  // Moduli used by the last step (at its mid-point volume fraction).
  const ContinuumModuli& last_moduli() const { return moduli_; }
  VolumeFractionUpdate update() const { return update_; }

 private:
  ContinuumConstants law_;
  VolumeFractionUpdate update_;
  double nu_ref_, nu_;
  Mat3 F_ = Mat3::Identity(), tau_;
  ContinuumModuli moduli_;
};

}  // namespace granular
