// Per-particle tables (n rows) reordered with the particles when they are sorted in cell
// order: wall histories, wall contact flags and rows, multi-contact wall rows.
#pragma once
#include <Kokkos_Core.hpp>

namespace granular {

// New row i of b is old row order(i) of a. A functor class rather than a lambda: nvcc's
// wrapper of a host-device lambda inside a function template instantiated in several
// translation units can be linked with a null copy helper (docs/perf_design_notes.md, GPU).
template <class View2D, class Order>
struct PermuteRowsPass {
  View2D b, a;
  Order order;
  int nc;
  KOKKOS_INLINE_FUNCTION void operator()(const int i) const {
    const int o = order(i);
    for (int c = 0; c < nc; ++c) b(i, c) = a(o, c);
  }
};

// Rows of a (n, c) view reordered with the particles: new row i is old row order(i).
template <class ExecSpace, class View2D, class Order>
void permute_rows(View2D& a, const Order& order, int n) {
  if (a.extent(0) == 0) return;
  View2D b(a.label(), a.extent(0), a.extent(1));
  Kokkos::parallel_for("dem::permute_rows", Kokkos::RangePolicy<ExecSpace>(0, n),
                       PermuteRowsPass<View2D, Order>{b, a, order, static_cast<int>(a.extent(1))});
  a = b;
}

}  // namespace granular
