// LAMMPS data file reader (see lammps_data.hpp).
#include "core/lammps/lammps_data.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <sstream>
#include <vector>

#include "core/run/error.hpp"

namespace granular {

namespace {
std::string strip_comment(const std::string& line) {
  const auto p = line.find('#');
  std::string s = p == std::string::npos ? line : line.substr(0, p);
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}
std::string number(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}
// One section's rows, flat: an id, `width` values (NaN where a line gave fewer) and the
// line number per row. A map of small vectors cost ~300 bytes per atom of heap that the
// process kept after reading; flat arrays cost ~70 and go back to the system.
struct SectionRows {
  int width;
  std::vector<long> id, line;
  std::vector<double> value;
  void add(long id_, long line_, const std::vector<double>& v) {
    id.push_back(id_), line.push_back(line_);
    for (int c = 0; c < width; ++c)
      value.push_back(c < static_cast<int>(v.size()) ? v[c] : std::nan(""));
  }
  size_t size() const { return id.size(); }
  const double* row(size_t r) const { return value.data() + r * width; }
  // Row indices in ascending id; a repeated id fails with both line numbers.
  std::vector<size_t> sorted(const std::string& path, const std::string& what) const {
    std::vector<size_t> order(size());
    for (size_t r = 0; r < order.size(); ++r) order[r] = r;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return id[a] < id[b]; });
    for (size_t q = 1; q < order.size(); ++q)
      if (id[order[q]] == id[order[q - 1]])
        throw InputError(path + ":" + std::to_string(line[order[q]]) + ": " + what + " " +
                         std::to_string(id[order[q]]) + " appears twice (also on line " +
                         std::to_string(line[order[q - 1]]) + ")");
    return order;
  }
};

// Where a data file is being read, so that a message names the file and the line.
struct DataCursor {
  const std::string& path;
  long line = 1;
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path + ":" + std::to_string(line) + ": " + what);
  }
};

// One line of the header: the tilt factors, the atom and type counts, or a pair of box bounds
// (any other header line is LAMMPS' business and is skipped).
void read_header_line(const std::string& s, double length_scale, const DataCursor& at,
                      LammpsData& out, long& natoms) {
  std::istringstream ss(s);
  double a, b, c;
  std::string w1, w2, w3;
  std::istringstream tt(s);
  if ((tt >> a >> b >> c >> w1 >> w2 >> w3) && w1 == "xy" && w2 == "xz" && w3 == "yz") {
    if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c))
      at.fail("the tilt factors xy xz yz must be finite numbers");
    out.tilt[0] = a * length_scale, out.tilt[1] = b * length_scale;
    out.tilt[2] = c * length_scale;
  } else if (s.find("atoms") != std::string::npos && s.find("types") == std::string::npos) {
    ss >> natoms;
  } else if (s.find("atom types") != std::string::npos) {
    if (!(ss >> out.atom_types) || out.atom_types < 1)
      at.fail("'atom types' needs a positive count");
  } else if ((ss >> a >> b >> w1 >> w2) && (w1 == "xlo" || w1 == "ylo" || w1 == "zlo")) {
    const int d = w1[0] - 'x';
    if (!std::isfinite(a) || !std::isfinite(b) || !(b > a))
      at.fail("the box bounds " + w1 + " " + w2 + " must be finite with " + w2 + " > " + w1);
    out.lo[d] = a * length_scale;
    out.len[d] = (b - a) * length_scale;
  }
}

// One row of the Atoms or Velocities section (an id, then numbers), checked and kept with its
// line; rows of other sections (Masses) are read for their numbers and dropped.
void read_section_row(const std::string& s, const std::string& section, int atom_types,
                      const DataCursor& at, SectionRows& atoms, SectionRows& vels) {
  std::istringstream ss(s);
  std::vector<double> v;
  double x;
  long id;
  if (!(ss >> id)) at.fail("expected an atom id");
  while (ss >> x) v.push_back(x);
  if (!ss.eof()) at.fail("not a number: '" + s + "'");
  // Positions, sizes and velocities enter cell indices and time steps: NaN or inf there
  // would be cast to an integer bin (undefined behaviour) instead of refused.
  for (double value : v)
    if (!std::isfinite(value)) at.fail("not a finite number: '" + s + "'");
  if (section == "Atoms") {
    if (v.size() < 6)
      at.fail("Atoms line needs: id type diameter density x y z (atom style sphere)");
    const int ntypes = std::min(atom_types, kLammpsMaxTypes);
    if (v[0] != std::floor(v[0]) || v[0] < 1 || v[0] > ntypes)
      at.fail("atom type " + number(v[0]) + " outside 1.." + std::to_string(ntypes) +
              " (atom types in the header, at most " + std::to_string(kLammpsMaxTypes) +
              " species)");
    if (!(v[1] > 0) || !(v[2] > 0)) at.fail("diameter and density must be positive");
    atoms.add(id, at.line, v);
  } else if (section == "Velocities") {
    if (v.size() < 3) at.fail("Velocities line needs: id vx vy vz [wx wy wz]");
    vels.add(id, at.line, v);
  }
}

// As many atoms as the header announced, each within the box's reach: atoms far outside it
// (LAMMPS keeps them within it, with image flags) are a damaged file, not a periodic image,
// refused with their line rather than binned at a wrong place.
void check_atoms(const std::string& path, long natoms, const SectionRows& atoms,
                 const LammpsData& out, double length_scale) {
  if (natoms < 0) throw InputError(path + ": header lacks the 'N atoms' line");
  if (static_cast<long>(atoms.size()) != natoms)
    throw InputError(path + ": header announces " + std::to_string(natoms) + " atoms, Atoms has " +
                     std::to_string(atoms.size()));
  for (size_t r = 0; r < atoms.size(); ++r)
    for (int d = 0; d < 3; ++d) {
      const double xd = atoms.row(r)[3 + d] * length_scale;
      if (out.len[d] > 0 && std::fabs(xd - out.lo[d] - 0.5 * out.len[d]) > 1e3 * out.len[d])
        throw InputError(path + ":" + std::to_string(atoms.line[r]) + ": atom " +
                         std::to_string(atoms.id[r]) + " lies " + "more than 1000 box lengths " +
                         "outside the box along " + std::string(1, static_cast<char>('x' + d)));
    }
}

// The particles in ascending id, in the engine's units, each with its velocity (and spin)
// where Velocities gives one; a velocity for an id that Atoms lacks is refused.
void fill_particles(const std::string& path, const SectionRows& atoms, const SectionRows& vels,
                    double length_scale, double time_scale, double mass_scale, LammpsData& out) {
  const std::vector<size_t> by_id = atoms.sorted(path, "atom id");
  const std::vector<size_t> vel_by_id = vels.sorted(path, "velocity of atom");
  HostParticles& h = out.particles;
  h.resize(static_cast<int>(atoms.size()));
  const double vscale = length_scale / time_scale;
  out.ids.reserve(atoms.size());
  size_t q = 0;  // next velocity row, in ascending id as the atoms
  for (int i = 0; i < static_cast<int>(by_id.size()); ++i) {
    const long id = atoms.id[by_id[i]];
    const double* a = atoms.row(by_id[i]);
    out.ids.push_back(id);
    h.species[i] = static_cast<int>(a[0]) - 1;
    h.radius[i] = 0.5 * a[1] * length_scale;
    h.density[i] = a[2] * (mass_scale / (length_scale * length_scale * length_scale));
    h.x[i] = a[3] * length_scale, h.y[i] = a[4] * length_scale, h.z[i] = a[5] * length_scale;
    if (q < vel_by_id.size() && vels.id[vel_by_id[q]] < id)
      break;  // a velocity for an id that Atoms skipped: reported below
    if (q < vel_by_id.size() && vels.id[vel_by_id[q]] == id) {
      const double* v = vels.row(vel_by_id[q++]);
      h.vx[i] = v[0] * vscale, h.vy[i] = v[1] * vscale, h.vz[i] = v[2] * vscale;
      if (!std::isnan(v[5]))
        h.wx[i] = v[3] / time_scale, h.wy[i] = v[4] / time_scale, h.wz[i] = v[5] / time_scale;
    }
  }
  if (q < vel_by_id.size())
    throw InputError(path + ": Velocities names atom " + std::to_string(vels.id[vel_by_id[q]]) +
                     ", which is not in Atoms");
}

}  // namespace

LammpsData read_lammps_data(const std::string& path, double length_scale, double time_scale,
                            double mass_scale) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open LAMMPS data file " + path);
  LammpsData out;
  long natoms = -1;
  std::string line;
  std::getline(in, line);                                 // the first line is a title
  SectionRows atoms{6, {}, {}, {}}, vels{6, {}, {}, {}};  // type d rho x y z; v, w
  std::string section;
  DataCursor at{path};
  while (std::getline(in, line)) {
    ++at.line;
    const std::string s = strip_comment(line);
    if (s.empty()) continue;
    if (s == "Atoms" || s == "Velocities" || s == "Masses")
      section = s;
    else if (section.empty())
      read_header_line(s, length_scale, at, out, natoms);
    else
      read_section_row(s, section, out.atom_types, at, atoms, vels);
  }
  check_atoms(path, natoms, atoms, out, length_scale);
  fill_particles(path, atoms, vels, length_scale, time_scale, mass_scale, out);
  return out;
}

std::string lammps_data_text(const HostParticles& h, const double lo[3], const double len[3],
                             const std::vector<long>& ids, double length_scale, double time_scale,
                             double mass_scale) {
  const int n = h.size();
  if (!ids.empty() && static_cast<int>(ids.size()) != n)
    throw InputError("LAMMPS data file: " + std::to_string(ids.size()) + " ids for " +
                     std::to_string(n) + " atoms");
  int types = 1;
  for (int i = 0; i < n; ++i) types = std::max(types, h.species[i] + 1);
  const double vscale = time_scale / length_scale,
               dscale = length_scale * length_scale * length_scale / mass_scale;
  char buf[512];
  std::string o = "LAMMPS data file (atom style sphere), written by granular\n\n";
  o += std::to_string(n) + " atoms\n" + std::to_string(types) + " atom types\n\n";
  const char* axis[3] = {"x", "y", "z"};
  for (int d = 0; d < 3; ++d) {
    std::snprintf(buf, sizeof buf, "%.17g %.17g %slo %shi\n", lo[d] / length_scale,
                  (lo[d] + len[d]) / length_scale, axis[d], axis[d]);
    o += buf;
  }
  o += "\nAtoms # sphere\n\n";
  for (int i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%ld %d %.17g %.17g %.17g %.17g %.17g\n",
                  ids.empty() ? static_cast<long>(i + 1) : ids[i], h.species[i] + 1,
                  2 * h.radius[i] / length_scale, h.density[i] * dscale, h.x[i] / length_scale,
                  h.y[i] / length_scale, h.z[i] / length_scale);
    o += buf;
  }
  o += "\nVelocities\n\n";
  for (int i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%ld %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  ids.empty() ? static_cast<long>(i + 1) : ids[i], h.vx[i] * vscale,
                  h.vy[i] * vscale, h.vz[i] * vscale, h.wx[i] * time_scale, h.wy[i] * time_scale,
                  h.wz[i] * time_scale);
    o += buf;
  }
  return o;
}

}  // namespace granular
