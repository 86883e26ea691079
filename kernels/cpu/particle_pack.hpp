// The packed per-particle records the frictional stream of the near list reads
// (kernels/cpu/near_stream.hpp), written by the kick-drift pass (KickDriftRows in
// kernels/dem/integrator.hpp) with the values it has just stored in the particle arrays. A record
// holds what a contact reads of a partner, in quarters of four doubles: x, y, z, radius |
// vx, vy, vz, mass | wx, wy, wz, 0: two cache lines where the separate arrays cost four (or
// five with the masses, which the Hertz law reads). The
// records are 32-byte aligned: the stream loads each quarter as one aligned vector.
#pragma once

namespace granular {

struct ParticlePack {
  static constexpr int kStride = 12;  // doubles per record
  // Where each quarter starts.
  static constexpr int kPosRadius = 0, kVelocity = 4, kSpin = 8;
};

}  // namespace granular
