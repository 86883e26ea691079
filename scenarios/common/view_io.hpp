// Kokkos Views to and from HDF5 datasets, bit for bit (doubles as doubles, ints as ints),
// for exact restarts (restart_file.hpp): a View is stored flat with its extents as attributes
// and read back into a View of the same extents, whatever they were when it was written.
#pragma once
#include <Kokkos_Core.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "core/io/output.hpp"
#include "core/run/error.hpp"

namespace granular {

template <class View>
void save_view(H5Writer& out, const std::string& name, const View& v) {
  using value = typename View::non_const_value_type;
  static_assert(View::rank <= 2, "rank 1 or 2 Views");
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  const size_t n0 = v.extent(0), n1 = View::rank == 2 ? v.extent(1) : 1;
  std::vector<value> flat(n0 * n1);
  for (size_t i = 0; i < n0; ++i)
    for (size_t j = 0; j < n1; ++j) {
      if constexpr (View::rank == 2)
        flat[i * n1 + j] = h(i, j);
      else
        flat[i] = h(i);
    }
  out.write(name, flat);
  out.attribute(name, "extent0", static_cast<double>(n0));
  out.attribute(name, "extent1", static_cast<double>(n1));
}

// Reads into `v`, reallocating it with the stored extents (a compile-time second extent
// must match) and its label (the dataset's name where it has none). Throws InputError on a
// missing dataset or mismatched shape.
template <class View>
void load_view(const H5Reader& in, const std::string& name, View& v) {
  using value = typename View::non_const_value_type;
  static_assert(std::is_same_v<value, double> || std::is_same_v<value, int>, "double or int");
  std::vector<value> flat;
  if constexpr (std::is_same_v<value, double>)
    flat = in.reals(name);
  else
    flat = in.ints(name);
  const auto n0 = static_cast<size_t>(in.attribute(name, "extent0"));
  const auto n1 = static_cast<size_t>(in.attribute(name, "extent1"));
  if (flat.size() != n0 * n1) throw InputError("restart dataset " + name + " has a wrong size");
  const std::string label = v.label().empty() ? name : v.label();
  if constexpr (View::rank == 2) {
    if constexpr (View::static_extent(1) != 0) {
      if (n1 != View::static_extent(1))
        throw InputError("restart dataset " + name + " has a wrong second extent");
      v = View(label, n0);
    } else {
      v = View(label, n0, n1);
    }
  } else {
    v = View(label, n0);
  }
  auto h = Kokkos::create_mirror_view(v);
  for (size_t i = 0; i < n0; ++i)
    for (size_t j = 0; j < n1; ++j) {
      if constexpr (View::rank == 2)
        h(i, j) = flat[i * n1 + j];
      else
        h(i) = flat[i];
    }
  Kokkos::deep_copy(v, h);
}

}  // namespace granular
