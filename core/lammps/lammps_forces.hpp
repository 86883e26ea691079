// Forces, torques and the pair virial of a LAMMPS data file under one of LAMMPS' granular
// pair styles (core/lammps/lammps_pair_styles.hpp), and velocity-Verlet steps as LAMMPS' `fix
// nve/sphere` takes them: the reference a user coming from LAMMPS compares against. Periodic
// orthogonal or triclinic boxes; contacts are found anew every step (no skin), so the
// shear history lives exactly as long as the contact, as in LAMMPS.
#pragma once
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/lammps/lammps_data.hpp"
#include "core/lammps/lammps_pair_styles.hpp"

namespace granular {

// LAMMPS' periodic box: edge vectors a = (lx, 0, 0), b = (xy, ly, 0), c = (xz, yz, lz).
struct LammpsBox {
  double lo[3] = {0, 0, 0};
  double edge[3][3] = {};  // edge[0] = a, edge[1] = b, edge[2] = c
  double volume() const { return edge[0][0] * edge[1][1] * edge[2][2]; }
  // Distance between the two faces spanned by the other two edges, per edge.
  double width(int d) const;
  // Fractional coordinates of a displacement.
  void fractional(const double d[3], double s[3]) const;
};

class LammpsForceField {
 public:
  LammpsForceField(const LammpsData& data, LammpsPairModel model, LammpsUnits units, double dt);

  // Forces and torques of the current state; `update` advances the shear history (a step),
  // without it the history is only read (LAMMPS' setup of a run).
  void compute(bool update);
  // One velocity-Verlet step of fix nve/sphere (solid spheres, inertia 2/5 m a^2).
  void step();

  int size() const { return static_cast<int>(id.size()); }
  double kinetic_energy() const;  // translational, sum m v^2 / 2 (LAMMPS' thermo ke)

  std::vector<long> id;
  std::vector<int> type;
  std::vector<double> radius, mass;
  std::vector<double> x, v, omega, force, torque;  // 3 per atom
  // Pair virial sum del (x) f over contacts: xx, yy, zz, xy, xz, yz (LAMMPS' order); the
  // pair pressure tensor is virial / volume * nktv2p.
  std::array<double, 6> virial{};
  long contacts = 0;
  long steps_done = 0;
  LammpsBox box;

 private:
  LammpsPairModel model_;
  LammpsUnits units_;
  double dt_;
  double cut_ = 0;  // largest contact distance, 2 a_max
  std::unordered_map<std::uint64_t, std::array<double, 3>> history_;

  // The force of the contact of atoms i < j at separation del (x_i - x_j of the touching
  // image), its history carried into `next`.
  void add_contact(int i, int j, const double del[3], double rsq, bool update,
                   std::unordered_map<std::uint64_t, std::array<double, 3>>& next);
};

}  // namespace granular
