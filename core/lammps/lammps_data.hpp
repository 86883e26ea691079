// Reader for LAMMPS data files of atom style sphere (LIGGGHTS "granular" has the same
// layout): `Atoms` lines `id type diameter density x y z [ix iy iz]`, optional
// `Velocities` lines `id vx vy vz wx wy wz`. Converts SI units to the engine's
// (mm, us, ug), sorts particles by id and unwraps nothing: positions are wrapped later.
// Atom type t becomes species t - 1, which must exist in the pair tables: 1 <= t <=
// min(atom types, kLammpsMaxTypes). Every malformed input is an InputError naming the file.
// Angular velocities (the last three Velocities columns) are kept in the particles' spins.
// A triclinic box (the `xy xz yz` header line) is read into `tilt`; the engine's own DEM box
// is cuboid, so its readers refuse it (the LAMMPS force reference takes it).
#pragma once
#include <string>
#include <vector>

#include "core/dem/host_particles.hpp"

namespace granular {

// The number of species the contact models' pair tables hold (kMaxSpecies in
// kernels/contact/contact_state.hpp, which needs Kokkos; a test asserts that they agree).
constexpr int kLammpsMaxTypes = 4;

struct LammpsData {
  HostParticles particles;
  double lo[3] = {0, 0, 0}, len[3] = {1, 1, 1};  // periodic box
  double tilt[3] = {0, 0, 0};                    // xy, xz, yz (zero: orthogonal box)
  std::vector<long> ids;                         // atom ids, ascending (particle order)
  int atom_types = 1;
  bool triclinic() const { return tilt[0] != 0 || tilt[1] != 0 || tilt[2] != 0; }
};

// `length_scale` multiplies lengths (1e3: metres to millimetres), `time_scale` times
// (1e6: seconds to microseconds), `mass_scale` masses (1e9: kilograms to micrograms);
// densities are multiplied by mass_scale / length_scale^3, which is 1 for the defaults
// (kg/m^3 equal ug/mm^3), and all three set to 1 read the file unchanged.
LammpsData read_lammps_data(const std::string& path, double length_scale = 1e3,
                            double time_scale = 1e6, double mass_scale = 1e9);

// The text of a data file of atom style sphere that read_lammps_data (with the same scales)
// and LAMMPS' `read_data` read back: species s becomes atom type s + 1, ids are 1..n in
// particle order (or `ids` where given), and the Velocities section holds the spins.
// The scales undo the reader's (the default writes SI from the engine's mm, us, ug).
std::string lammps_data_text(const HostParticles& particles, const double lo[3],
                             const double len[3], const std::vector<long>& ids = {},
                             double length_scale = 1e3, double time_scale = 1e6,
                             double mass_scale = 1e9);

}  // namespace granular
