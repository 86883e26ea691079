// The contact network of a DEM state: one row per touching pair (identities i < j), with the
// branch vector from i to j, the normal force (positive: repulsive), the tangential force on i
// and the overlap, from the contact model's elastic forces and each contact's history. Read on
// the host (mirrors are the arrays themselves in a host build). Used by the library API and
// by snapshot series that record the network per frame.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <vector>

#include "kernels/dem/dem_system.hpp"

namespace granular {

struct ContactNetwork {
  std::vector<int> i, j;
  std::vector<double> branch, normal_force, tangential_force;  // 3, 1 and 3 per contact
  std::vector<double> overlap;
  int size() const { return static_cast<int>(i.size()); }
};

template <class System>
ContactNetwork contact_network(const System& sys) {
  // Read on the host (mirrors are the arrays themselves in a host build): what pair_state
  // needs of the particles, the neighbour list's rows and the contact history.
  const auto host = Kokkos::HostSpace();
  const auto& p = sys.particles();
  const auto& nl = sys.neighbor_list();
  const struct {
    decltype(Kokkos::create_mirror_view_and_copy(host, p.x)) x, v, w;
    decltype(Kokkos::create_mirror_view_and_copy(host, p.radius)) radius, mass;
    decltype(Kokkos::create_mirror_view_and_copy(host, p.species)) species;
  } pv{Kokkos::create_mirror_view_and_copy(host, p.x),
       Kokkos::create_mirror_view_and_copy(host, p.v),
       Kokkos::create_mirror_view_and_copy(host, p.w),
       Kokkos::create_mirror_view_and_copy(host, p.radius),
       Kokkos::create_mirror_view_and_copy(host, p.mass),
       Kokkos::create_mirror_view_and_copy(host, p.species)};
  const auto id = Kokkos::create_mirror_view_and_copy(host, p.id);
  const auto off = Kokkos::create_mirror_view_and_copy(host, nl.offsets());
  const auto own = Kokkos::create_mirror_view_and_copy(host, nl.owned_end());
  const auto nb = Kokkos::create_mirror_view_and_copy(host, nl.neighbors());
  const auto pb = Kokkos::create_mirror_view_and_copy(host, nl.pair_begin());
  const auto hist = Kokkos::create_mirror_view_and_copy(host, sys.history_view());
  const PeriodicBox b = sys.box();
  const double zero[3] = {0, 0, 0};
  constexpr int H = System::model_type::history;
  struct Row {
    int a, b;
    double branch[3], fn, ft[3], delta;
  };
  std::vector<Row> rows;
  for (int i = 0; i < p.n; ++i)
    for (int k = off(i); k < own(i); ++k) {  // each pair once, from its owner
      const int j = nb(k);
      PairState s;
      if (!pair_state(pv, b, zero, System::model_type::rotations, i, j, s)) continue;
      double h[H > 0 ? H : 1] = {};
      if constexpr (H > 0)
        for (int q = 0; q < H; ++q) h[q] = hist(pb(i) + (k - off(i)), q);
      PairForce e;
      sys.model().elastic(s, h, e);
      Row r;
      const double l = s.ai + s.aj - s.delta;  // centre distance; n points from j to i
      const bool flip = id(i) > id(j);         // rows are (lower id, higher id)
      r.a = flip ? id(j) : id(i);
      r.b = flip ? id(i) : id(j);
      for (int d = 0; d < 3; ++d) {
        r.branch[d] = (flip ? l : -l) * s.n[d];  // from a to b
        r.ft[d] = flip ? -e.ft[d] : e.ft[d];     // on a
      }
      r.fn = e.fn;
      r.delta = s.delta;
      rows.push_back(r);
    }
  std::sort(rows.begin(), rows.end(),
            [](const Row& x, const Row& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
  ContactNetwork c;
  for (const Row& r : rows) {
    c.i.push_back(r.a), c.j.push_back(r.b);
    c.branch.insert(c.branch.end(), r.branch, r.branch + 3);
    c.tangential_force.insert(c.tangential_force.end(), r.ft, r.ft + 3);
    c.normal_force.push_back(r.fn);
    c.overlap.push_back(r.delta);
  }
  return c;
}

}  // namespace granular
