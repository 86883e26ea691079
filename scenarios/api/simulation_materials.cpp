// The library API's simulation under the Hertz law of named materials with restitution
// damping, without friction and with the Mindlin tangential law (scenarios/common/materials.hpp).
#include "scenarios/api/simulation_impl.hpp"

namespace granular::api {

GRANULAR_SIMULATION_OF(ContactModel<HertzRestitutionNormal, NoTangential, NoRolling>)
GRANULAR_SIMULATION_OF(ContactModel<HertzRestitutionNormal, CoulombTangential, NoRolling>)

}  // namespace granular::api
