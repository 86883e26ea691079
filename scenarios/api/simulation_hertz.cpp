// The library API's simulation under the hertz normal law, without friction, with Coulomb
// friction, and with friction and rolling resistance (one compilation of their kernels).
#include "scenarios/api/simulation_impl.hpp"

namespace granular::api {

GRANULAR_SIMULATION_OF(ContactModel<HertzNormal, NoTangential, NoRolling>)
GRANULAR_SIMULATION_OF(ContactModel<HertzNormal, CoulombTangential, NoRolling>)
GRANULAR_SIMULATION_OF(ContactModel<HertzNormal, CoulombTangential, RollingTorsion>)

}  // namespace granular::api
