// How many slabs the host force pass cuts the box into where a neighbour list is not given a
// count of its own (NeighborList::set_partition).
#pragma once

namespace granular {

// Six (two per round of three) unless the process asks for another (granular run
// --force-slabs). Only a third of the slabs run at once, so hosts with more than two threads
// want more of them; thinner slabs read their neighbours' outer layers again in other rounds.
inline int& default_force_slabs() {
  static int slabs = 6;
  return slabs;
}

}  // namespace granular
