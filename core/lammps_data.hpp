// Reader for LAMMPS data files of atom style sphere (LIGGGHTS "granular" has the same
// layout): `Atoms` lines `id type diameter density x y z [ix iy iz]`, optional
// `Velocities` lines `id vx vy vz wx wy wz`. Converts SI units to the engine's
// (mm, us, ug), sorts particles by id and unwraps nothing: positions are wrapped later.
#pragma once
#include <string>

#include "core/host_particles.hpp"

namespace granular {

struct LammpsData {
  HostParticles particles;
  double lo[3] = {0, 0, 0}, len[3] = {1, 1, 1};  // periodic box
  int atom_types = 1;
};

// `length_scale` multiplies lengths (1e3: metres to millimetres), `time_scale` times
// (1e6: seconds to microseconds); densities in kg/m^3 equal ug/mm^3 and need no factor.
LammpsData read_lammps_data(const std::string& path, double length_scale = 1e3,
                            double time_scale = 1e6);

}  // namespace granular
