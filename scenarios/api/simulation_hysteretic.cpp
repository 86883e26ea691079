// The library API's simulation under the hysteretic normal law, without friction, with Coulomb
// friction, and with friction and rolling resistance (one compilation of their kernels).
#include "scenarios/api/simulation_impl.hpp"

namespace granular::api {

GRANULAR_SIMULATION_OF(ContactModel<HystereticNormal, NoTangential, NoRolling>)
GRANULAR_SIMULATION_OF(ContactModel<HystereticNormal, CoulombTangential, NoRolling>)
GRANULAR_SIMULATION_OF(ContactModel<HystereticNormal, CoulombTangential, RollingTorsion>)

}  // namespace granular::api
