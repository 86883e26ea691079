// LAMMPS' granular pair styles in LAMMPS' own terms, for users who bring a LAMMPS deck:
// `gran/hooke`, `gran/hooke/history`, `gran/hertz/history` (mass-scaled dashpots, dampflag,
// limit_damping) and `granular` with the normal models hooke, hertz, hertz/material, the
// damping models velocity, mass_velocity, viscoelastic, tsuji, and the tangential models
// linear_nohistory, linear_history, mindlin. The formulas follow the LAMMPS version Debian 12
// ships (the one the peer benchmark installs): contact point at the particle surface
// (lever arms a_i, a_j) for the gran/* styles and mid-overlap for `granular`, the shear
// history projected after it is advanced (gran/*) or rotated with its length kept before
// (`granular`), and no history update while a run sets up. They differ from the engine's
// native laws in those details; the `lammps_forces` scene evaluates them, with no physics of
// the engine's own, so that a deck's forces can be reproduced to round-off.
#pragma once
#include <string>
#include <vector>

namespace granular {

// LAMMPS' unit-style constants that enter these styles: force*time/mass to velocity (the
// integrator) and the pressure conversion (gran/hertz/history's stiffnesses, the virial).
struct LammpsUnits {
  std::string style;
  double ftm2v = 1, nktv2p = 1;
};
// lj, real, metal, si, cgs, electron, micro, nano; anything else is an InputError.
LammpsUnits lammps_units(const std::string& style);

enum class LammpsStyle { GranHooke, GranHookeHistory, GranHertzHistory, Granular };

// One type pair of `pair_style granular`.
struct GranularPair {
  enum Normal { Hooke, Hertz, HertzMaterial } normal = Hooke;
  enum Damping { Velocity, MassVelocity, Viscoelastic, Tsuji } damping = Viscoelastic;
  enum Tangential { LinearNoHistory, LinearHistory, Mindlin } tangential = LinearHistory;
  double kn = 0;    // hooke/hertz stiffness, or 4/3 E* for hertz/material
  double damp = 0;  // normal damping coefficient (tsuji: converted from the restitution)
  double kt = 0;    // tangential stiffness (mindlin: times a = sqrt(R delta) per contact)
  double xgt = 0;   // tangential damping as a multiple of the normal one
  double mu = 0;    // friction coefficient
  bool limit_damping = false;
  bool set = false;
};

struct LammpsPairModel {
  LammpsStyle style = LammpsStyle::GranHooke;
  int ntypes = 1;
  // gran/* styles (one set for all types)
  double kn = 0, kt = 0, gamman = 0, gammat = 0, xmu = 0;
  int dampflag = 1;
  bool limit_damping = false;
  // granular: (ntypes + 1)^2 entries indexed [i * (ntypes + 1) + j], types from 1
  std::vector<GranularPair> pairs;
  const GranularPair& pair(int ti, int tj) const { return pairs[ti * (ntypes + 1) + tj]; }
  bool history() const;  // contacts carry a 3-vector shear history
  std::string describe() const;
};

// `pair_style` and `pair_coeff` lines as written in a LAMMPS deck, without the command word
// ("gran/hooke/history 1e8 NULL 2.387e5 NULL 0.5 1", "* * hooke 1e8 1 tangential ...").
// Every unsupported or malformed argument is an InputError that says what is accepted.
LammpsPairModel parse_lammps_pair(const std::string& pair_style,
                                  const std::vector<std::string>& pair_coeffs, int ntypes,
                                  const LammpsUnits& units);

// One contact as LAMMPS sees it: del = x_i - x_j (the image in contact), rsq = |del|^2 <
// (r_i + r_j)^2, velocities and spins of both atoms, radii, masses and types.
struct LammpsContactIn {
  double del[3], rsq;
  const double *vi, *vj, *wi, *wj;
  double ri, rj, mi, mj;
  int ti, tj;
};
struct LammpsContactOut {
  double f[3];  // force on i (j gets -f)
  double torque_i[3], torque_j[3];
};

// Evaluates one touching pair; `history` (3 doubles, zero for a new contact) is advanced
// when `update` is set (every step, not while a run sets up).
void lammps_contact(const LammpsPairModel& m, const LammpsContactIn& c, double dt, bool update,
                    double* history, LammpsContactOut& out);

}  // namespace granular
