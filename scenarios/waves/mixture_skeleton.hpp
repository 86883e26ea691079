// The load-bearing skeleton of a two-species packing (docs/guide_waves.md, "The glass
// skeleton"): which contacts carry the pressure, how many contacts of each kind a
// particle has, and whether the stiff–stiff contacts form a network that spans the periodic box.
//
// The pressure share of a contact type is its part of P = (1/3V) sum_c f_n,c l_c, the normal
// force times the centre distance summed over the touching pairs of that type (the tangential
// force is normal to the branch vector and adds nothing to the trace). The stiff–stiff network
// percolates when one of its clusters wraps around the box: following its contacts from one
// particle back to itself adds a whole box length along some axis.
#pragma once
#include <vector>

#include "scenarios/common/contact_network.hpp"

namespace granular {

struct Skeleton {
  // Share of the pressure carried by stiff–stiff, stiff–soft and soft–soft contacts (sum 1;
  // NaN without any load).
  double share[3] = {0, 0, 0};
  // Contacts per particle: stiff partners of a stiff particle, soft partners of a stiff one,
  // stiff partners of a soft one, soft partners of a soft one (NaN without such particles).
  double z_stiff_stiff = 0, z_stiff_soft = 0, z_soft_stiff = 0, z_soft_soft = 0;
  int contacts[3] = {0, 0, 0};  // touching pairs by type, as `share`
  // The largest cluster of stiff particles joined by stiff–stiff contacts, as a fraction of
  // the stiff particles, and the number of axes (0-3) along which it wraps around the box.
  double largest_cluster = 0;
  int wrapping_axes = 0;
};

// `net`: touching pairs by identity (contact_network); `species` and `position` (3 per
// particle) by identity; `len`: the box's edges (an orthogonal periodic box).
Skeleton measure_skeleton(const ContactNetwork& net, const std::vector<int>& species,
                          const std::vector<double>& position, const double len[3], int stiff);

}  // namespace granular
