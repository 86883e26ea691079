// LAMMPS dump files (see lammps_dump.hpp).
#include "core/lammps/lammps_dump.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "core/run/error.hpp"

namespace granular {

std::string lammps_dump_text(const LammpsDumpFrame& f) {
  const size_t nc = f.columns.size();
  if (nc == 0 || f.values.size() % nc != 0)
    throw InputError("LAMMPS dump: " + std::to_string(f.values.size()) +
                     " values do not fill rows of " + std::to_string(nc) + " columns");
  std::vector<bool> integer(nc);
  for (size_t c = 0; c < nc; ++c)
    integer[c] = f.columns[c] == "id" || f.columns[c] == "type" || f.columns[c] == "mol" ||
                 f.columns[c] == "proc";
  std::ostringstream o;
  o << "ITEM: TIMESTEP\n" << f.step << "\nITEM: NUMBER OF ATOMS\n" << f.atoms() << '\n';
  o << "ITEM: BOX BOUNDS ";
  if (f.triclinic) o << "xy xz yz ";
  for (int d = 0; d < 3; ++d) o << (f.periodic[d] ? "pp" : "ff") << (d < 2 ? ' ' : '\n');
  char buf[64];
  auto num = [&](double x) {
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return std::string(buf);
  };
  const double xy = f.triclinic ? f.tilt[0] : 0, xz = f.triclinic ? f.tilt[1] : 0,
               yz = f.triclinic ? f.tilt[2] : 0;
  // The bounding box of the cell along x and y (LAMMPS' xlo_bound ... yhi_bound).
  const double xlo = f.lo[0] + std::min({0.0, xy, xz, xy + xz});
  const double xhi = f.lo[0] + f.len[0] + std::max({0.0, xy, xz, xy + xz});
  const double ylo = f.lo[1] + std::min(0.0, yz), yhi = f.lo[1] + f.len[1] + std::max(0.0, yz);
  const double bounds[3][2] = {{xlo, xhi}, {ylo, yhi}, {f.lo[2], f.lo[2] + f.len[2]}};
  for (int d = 0; d < 3; ++d) {
    o << num(bounds[d][0]) << ' ' << num(bounds[d][1]);
    if (f.triclinic) o << ' ' << num(f.tilt[d]);
    o << '\n';
  }
  o << "ITEM: ATOMS";
  for (const std::string& c : f.columns) o << ' ' << c;
  o << '\n';
  for (size_t r = 0; r < f.values.size() / nc; ++r) {
    for (size_t c = 0; c < nc; ++c) {
      const double x = f.values[r * nc + c];
      if (c) o << ' ';
      if (integer[c])
        o << static_cast<long long>(x);
      else
        o << num(x);
    }
    o << '\n';
  }
  return o.str();
}

}  // namespace granular
