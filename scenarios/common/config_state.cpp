// Saved configurations as HDF5 files (see config_state.hpp). Layout:
//   /state/{position, velocity, angular_velocity} (n x 3), /state/{radius, mass, density},
//   /state/species, /state/box_lo, /state/box_len, attributes phi, pressure;
//   /contacts/{pair_i, pair_j} and /contacts/history (M x width), attribute history_width.
#include "scenarios/common/config_state.hpp"

#include <cmath>

#include "core/io/dataset_units.hpp"
#include "kernels/contact/contact_state.hpp"

namespace granular {

namespace {
std::vector<double> interleave(const std::vector<double>& a, const std::vector<double>& b,
                               const std::vector<double>& c) {
  std::vector<double> out(3 * a.size());
  for (size_t i = 0; i < a.size(); ++i)
    out[3 * i] = a[i], out[3 * i + 1] = b[i], out[3 * i + 2] = c[i];
  return out;
}
void split(const std::vector<double>& in, std::vector<double>& a, std::vector<double>& b,
           std::vector<double>& c, const std::string& path, const char* what) {
  if (in.size() != 3 * a.size())  // checked before reading: a short array must not be overrun
    throw InputError("configuration file " + path + ": " + what + " has " +
                     std::to_string(in.size()) + " values for " + std::to_string(a.size()) +
                     " particles");
  for (size_t i = 0; i < a.size(); ++i)
    a[i] = in[3 * i], b[i] = in[3 * i + 1], c[i] = in[3 * i + 2];
}
}  // namespace

void write_config(const std::string& path, const ConfigState& c) {
  const HostParticles& p = c.particles;
  const hsize_t n = static_cast<hsize_t>(c.size());
  H5Writer out(path);
  // The engine's units: mm, us, ug.
  write_quantity(out, "/state/position", interleave(p.x, p.y, p.z), "mm", {n, 3});
  write_quantity(out, "/state/velocity", interleave(p.vx, p.vy, p.vz), "mm us-1", {n, 3});
  write_quantity(out, "/state/angular_velocity", c.w, "rad us-1", {n, 3});
  write_quantity(out, "/state/radius", p.radius, "mm");
  write_quantity(out, "/state/mass", c.mass, "ug");
  write_quantity(out, "/state/density", p.density, "ug mm-3");
  write_quantity(out, "/state/species", p.species, "1");
  write_quantity(out, "/state/box_lo", std::vector<double>(c.box.lo, c.box.lo + 3), "mm");
  write_quantity(out, "/state/box_len", std::vector<double>(c.box.len, c.box.len + 3), "mm");
  out.attribute("/state", "phi", c.phi);
  out.attribute("/state", "pressure", c.pressure);
  out.attribute("/state", "format", std::string("granular configuration 1"));
  out.attribute("/contacts", "history_width", static_cast<double>(c.history_width));
  if (!c.pair_i.empty()) {
    const hsize_t m = c.pair_i.size(), w = static_cast<hsize_t>(c.history_width);
    write_quantity(out, "/contacts/pair_i", c.pair_i, "1");
    write_quantity(out, "/contacts/pair_j", c.pair_j, "1");
    // No unit: each contact law keeps its own mix of values in a history row (spring
    // displacements, largest overlaps, ...), which this file does not name.
    out.write("/contacts/history", c.history, {m, w});
  }
  out.commit();
}

ConfigState read_config(const std::string& path) {
  H5Reader in(path);
  ConfigState c;
  const auto radius = in.reals("/state/radius");
  const int n = static_cast<int>(radius.size());
  HostParticles& p = c.particles;
  p.resize(n);
  p.radius = radius;
  split(in.reals("/state/position"), p.x, p.y, p.z, path, "position");
  split(in.reals("/state/velocity"), p.vx, p.vy, p.vz, path, "velocity");
  p.density = in.reals("/state/density");
  p.species = in.ints("/state/species");
  c.w = in.reals("/state/angular_velocity");
  c.mass = in.reals("/state/mass");
  const auto lo = in.reals("/state/box_lo"), len = in.reals("/state/box_len");
  if (p.density.size() != radius.size() || p.species.size() != radius.size() ||
      c.w.size() != 3 * radius.size() || c.mass.size() != radius.size() || lo.size() != 3 ||
      len.size() != 3)
    throw InputError("configuration file " + path + " is inconsistent (array sizes differ)");
  for (int d = 0; d < 3; ++d) c.box.lo[d] = lo[d], c.box.len[d] = len[d];
  c.phi = in.attribute("/state", "phi");
  c.pressure = in.attribute("/state", "pressure");
  const double width = in.attribute("/contacts", "history_width");
  if (!(width >= 0 && width <= 64) || width != std::floor(width))
    throw InputError("configuration file " + path + ": contact history width is not a whole " +
                     "number in [0, 64]");
  c.history_width = static_cast<int>(width);
  if (in.has("/contacts/pair_i")) {
    c.pair_i = in.ints("/contacts/pair_i");
    c.pair_j = in.ints("/contacts/pair_j");
    c.history = in.reals("/contacts/history");
    if (c.pair_j.size() != c.pair_i.size() ||
        c.history.size() != c.pair_i.size() * static_cast<size_t>(c.history_width))
      throw InputError("configuration file " + path + " has inconsistent contact history");
    for (size_t r = 0; r < c.pair_i.size(); ++r)
      if (c.pair_i[r] < 0 || c.pair_i[r] >= n || c.pair_j[r] < 0 || c.pair_j[r] >= n)
        throw InputError("configuration file " + path + ": contact " + std::to_string(r) +
                         " names a particle that does not exist");
  }
  for (int i = 0; i < n; ++i)
    if (p.species[i] < 0 || p.species[i] >= kMaxSpecies)
      throw InputError("configuration file " + path + ": particle " + std::to_string(i) +
                       " has species " + std::to_string(p.species[i]) + ", outside [0, " +
                       std::to_string(kMaxSpecies) + ")");
  // Every number finite, sizes and masses positive: a damaged file must be refused here, not
  // turn into NaN forces (or a run that ends with null results) later.
  auto refuse = [&](const std::string& what, size_t i) {
    throw InputError("configuration file " + path + ": " + what + " of particle " +
                     std::to_string(i) + " is not a finite number" +
                     (what == "radius" || what == "density" || what == "mass" ? " above 0" : ""));
  };
  for (int i = 0; i < n; ++i) {
    const double xyz[] = {p.x[i], p.y[i], p.z[i]}, v[] = {p.vx[i], p.vy[i], p.vz[i]};
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(xyz[d])) refuse("the position", i);
      if (!std::isfinite(v[d])) refuse("the velocity", i);
      if (!std::isfinite(c.w[3 * i + d])) refuse("the angular velocity", i);
    }
    if (!(std::isfinite(p.radius[i]) && p.radius[i] > 0)) refuse("radius", i);
    if (!(std::isfinite(p.density[i]) && p.density[i] > 0)) refuse("density", i);
    if (!(std::isfinite(c.mass[i]) && c.mass[i] > 0)) refuse("mass", i);
  }
  for (int d = 0; d < 3; ++d)
    if (!std::isfinite(c.box.lo[d]) || !(std::isfinite(c.box.len[d]) && c.box.len[d] > 0))
      throw InputError("configuration file " + path + ": the box is not finite and positive");
  for (size_t r = 0; r < c.history.size(); ++r)
    if (!std::isfinite(c.history[r]))
      throw InputError("configuration file " + path + ": contact history entry " +
                       std::to_string(r) + " is not a finite number");
  return c;
}

ConfigState config_from_packing(HostParticles particles, const PeriodicBox& box) {
  ConfigState c;
  const int n = particles.size();
  c.w.resize(3 * static_cast<size_t>(n));
  c.mass.resize(n);
  double volume = 0;
  for (int i = 0; i < n; ++i) {
    const double a = particles.radius[i];
    c.w[3 * i] = particles.wx[i], c.w[3 * i + 1] = particles.wy[i],
            c.w[3 * i + 2] = particles.wz[i];
    c.mass[i] = particles.density[i] * 4.0 / 3.0 * M_PI * a * a * a;  // as Particles::from_host
    volume += 4.0 / 3.0 * M_PI * a * a * a;
  }
  c.particles = std::move(particles);
  c.box = box;
  c.phi = volume / box.volume();
  return c;
}

}  // namespace granular
