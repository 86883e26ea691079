// The convected stress update of one material point.
#include "core/continuum/material_point.hpp"

#include <cmath>
#include <sstream>

#include "core/run/error.hpp"

namespace granular {

MaterialPoint::MaterialPoint(const ContinuumConstants& law, double nu_start,
                             VolumeFractionUpdate update, const Mat3& tau_start)
    : law_(law), update_(update), nu_ref_(nu_start), nu_(nu_start), tau_(tau_start) {
  law_.check();
  if (!(nu_start > 0 && nu_start < 1))
    throw InputError("material point: start volume fraction must lie in (0, 1)");
  moduli_ = continuum_moduli(law_, nu_);
}

double MaterialPoint::deviatoric() const {
  const Mat3 s = cauchy();
  const Mat3 dev = s - s.trace() / 3.0 * Mat3::Identity();
  return std::sqrt(1.5 * dev.cwiseProduct(dev).sum());
}

void MaterialPoint::step_to(const Mat3& F_next) {
  const double J0 = F_.determinant(), J1 = F_next.determinant();
  if (!(J1 > 0)) {
    std::ostringstream msg;
    msg << "material point: deformation gradient with det F = " << J1
        << " (must be positive) after volume fraction " << nu_;
    throw InputError(msg.str());
  }
  const Mat3 f = F_next * F_.inverse();
  const Mat3 I = Mat3::Identity();
  const Mat3 e = 0.5 * (I - (f * f.transpose()).inverse());
  // Moduli at the step's mid-point volume: evaluating them at either end would add an error
  // of first order in the step to the pressure-dependent stiffness.
  moduli_ = continuum_moduli(law_, volume_fraction(update_, nu_ref_, 0.5 * (J0 + J1)));
  const double tr = e.trace();
  const Mat3 ae = moduli_.K * tr * I + 2.0 * moduli_.G * (e - tr / 3.0 * I);
  tau_ = f * tau_ * f.transpose() + ae;
  F_ = F_next;
  nu_ = volume_fraction(update_, nu_ref_, J1);
  // Below jamming there is no contact network to carry load: the state is stress-free
  // (otherwise the convected term would carry a stale stress into the gas).
  if (nu_ < law_.nu0) tau_.setZero();
}

}  // namespace granular
