// Every dataset of a scene's results.h5 carries its unit: a UTF-8 text attribute `unit`, in
// the H5MD spelling (symbols with space-separated powers: "mm", "mm us-1", "MPa", "mJ",
// "ug mm-3") and "1" for a pure number (counts, ids, flags, ratios, fractions, exponents,
// quantities made dimensionless by the scene's scales). The engine's units are mm, us and ug,
// so forces are in N, stresses in MPa and energies in mJ; docs/data_formats.md lists the
// spellings and the scales of the scenes written in reduced units.
#pragma once
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/io/output.hpp"

namespace granular {

// Labels a dataset already written (columns written by a loop, datasets written by a helper).
inline void set_unit(H5Writer& out, const std::string& dataset, const std::string& unit) {
  if (unit.empty())
    throw std::logic_error("dataset " + dataset + " written without a unit (use \"1\")");
  out.attribute_utf8(dataset, "unit", unit);
}

// Writes dataset `name` and its unit.
template <class T>
void write_quantity(H5Writer& out, const std::string& name, const std::vector<T>& data,
                    const std::string& unit, std::vector<hsize_t> dims = {}) {
  out.write(name, data, std::move(dims));
  set_unit(out, name, unit);
}

}  // namespace granular
