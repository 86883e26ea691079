// The chain contact law (docs/model_chains.md), written once for both Verlet kernels: the
// sweep over global arrays (chain_verlet.hpp) and the on-chip one (chain_on_chip.hpp).
#pragma once
#include <Kokkos_Core.hpp>

#include "kernels/chain/chain_batch.hpp"

namespace granular {

// Force that contact c pushes onto its right bead (and pulls from its left bead), given
// the relative displacement du = u_left - u_right; also reports the overlap.
template <ChainForce Law>
struct ChainContactForce {
  KOKKOS_INLINE_FUNCTION static double eval(double kappa, double delta0, double klin, double du,
                                            double& overlap) {
    overlap = delta0 + du;
    if constexpr (Law == ChainForce::Hertz) {
      // Static part included: kappa delta0^{3/2} = 1 on every contact, so it cancels.
      return overlap > 0.0 ? kappa * overlap * Kokkos::Experimental::sqrt(overlap) : 0.0;
    } else {
      (void)kappa;
      return klin * du;  // the constant static force cancels between the two sides
    }
  }
};

}  // namespace granular
