// The engine's own contact law that a LAMMPS `pair_style granular` model is, term for term,
// where one exists: what lets a LAMMPS deck's physics run on the engine's fast pair loops
// instead of the `lammps_forces` reference (which evaluates LAMMPS' formulas one pair at a
// time), and what the peer benchmark times against LAMMPS (perf/peer/bench.lmp, hertz_tsuji).
//
//   hertz/material E e nu  damping tsuji  tangential mindlin NULL|k_t x_gt mu
//     = HertzRestitutionNormal      K = (4/3) E*, alpha = Tsuji's coefficient of e
//       + CoulombTangential::MindlinRestitution  k_t sqrt(R delta), gamma_t = g sqrt(m* k_t),
//         g = x_gt alpha sqrt(K / k_t)  (LAMMPS' tangential dashpot is x_gt times the normal one,
//         alpha sqrt(m* K a))
//
// Both put the contact point mid-overlap for the torques and limit the tangential force by mu
// times the total normal force. They differ in three details, all measured by
// tests/scenarios/lammps/test_native_laws.cpp:
//  - the spin's share of the contact-point velocity: LAMMPS takes r_i w_i + r_j w_j, the engine
//    the lever arms a - delta/2 (kernels/dem/contact_forces.hpp: pair_geometry), a relative
//    difference of delta/(2a) in that term only; without spin the forces agree to round-off;
//  - after a slip the engine's spring keeps the elastic share of the force only (the
//    restitution-damped Mindlin law, kernels/contact/contact_state.hpp: coulomb_spring), LAMMPS'
//    also the dashpot's; the force of the slipping step is the same;
//  - LAMMPS turns the spring into the tangent plane only when it has left it by more than
//    1e-10 of the sliding limit, the engine every step (both keep its length).
#pragma once
#include <cmath>
#include <string>

#include "core/lammps/lammps_pair_styles.hpp"
#include "core/run/error.hpp"
#include "kernels/contact/contact_model.hpp"

namespace granular {

using NativeHertzTsuji = ContactModel<HertzRestitutionNormal, CoulombTangential, NoRolling>;

// `pressure_to_engine` converts the deck's pressure unit to the engine's (SI Pa to MPa of the
// engine's mm-us-ug units: 1e-6); every other coefficient of the law is a pure number.
inline NativeHertzTsuji native_hertz_tsuji(const GranularPair& p, double pressure_to_engine) {
  if (p.normal != GranularPair::HertzMaterial || p.damping != GranularPair::Tsuji ||
      p.tangential != GranularPair::Mindlin || p.limit_damping || !(p.kt > 0))
    throw InputError(
        "the engine's restitution-damped Hertz-Mindlin law is LAMMPS' `hertz/material ... "
        "damping tsuji tangential mindlin ...` with k_t > 0 and without limit_damping; this pair "
        "is not");
  const double K = p.kn * pressure_to_engine, kt = p.kt * pressure_to_engine;
  const double gt = p.xgt * p.damp * std::sqrt(p.kn / p.kt);
  return {HertzRestitutionNormal::uniform(K, p.damp),
          CoulombTangential::uniform(kt, gt, p.mu, p.mu, CoulombTangential::MindlinRestitution),
          {}};
}

}  // namespace granular
