// Random gas generator (see packing.hpp). Host code: it runs once per scene.
#include "scenarios/common/packing.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "core/lammps/lammps_data.hpp"
#include "core/run/error.hpp"
#include "core/run/rng.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/packing_file.hpp"

namespace granular {

HostParticles random_gas(const GasSpec& s, PeriodicBox& box) {
  if (s.count < 1) throw InputError("particle count must be positive");
  if (!(s.diameter_min > 0) || s.diameter_max < s.diameter_min)
    throw InputError("diameters must satisfy 0 < diameter_min <= diameter_max");
  if (!(s.phi > 0) || s.phi > kMaxGasFraction)
    throw InputError("gas volume fraction must be in (0, 0.45]: random insertion jams above");
  const int n = s.count;
  HostParticles h;
  h.resize(n);
  double vol = 0.0;
  for (int i = 0; i < n; ++i) {
    Stream st(s.seed, static_cast<std::uint64_t>(i));
    const double d = st.uniform(s.diameter_min, s.diameter_max);
    h.radius[i] = 0.5 * d;
    h.density[i] = s.density;
    vol += M_PI / 6.0 * d * d * d;
    h.vx[i] = s.speed * st.normal();
    h.vy[i] = s.speed * st.normal();
    h.vz[i] = s.speed * st.normal();
  }
  const double edge = std::cbrt(vol / s.phi);
  for (int d = 0; d < 3; ++d) box.lo[d] = 0.0, box.len[d] = edge;

  // Zero total momentum, so the gas does not drift through the box.
  double p[3] = {0, 0, 0}, mtot = 0;
  for (int i = 0; i < n; ++i) {
    const double m = h.density[i] * std::pow(h.radius[i], 3);
    p[0] += m * h.vx[i], p[1] += m * h.vy[i], p[2] += m * h.vz[i];
    mtot += m;
  }
  for (int i = 0; i < n; ++i)
    h.vx[i] -= p[0] / mtot, h.vy[i] -= p[1] / mtot, h.vz[i] -= p[2] / mtot;

  // Grid hash with cells no smaller than the largest diameter.
  const int nc = std::max(1, static_cast<int>(edge / s.diameter_max));
  const double cl = edge / nc;
  std::vector<std::vector<int>> cells(static_cast<size_t>(nc) * nc * nc);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return h.radius[a] > h.radius[b]; });
  const PeriodicBox b = box;
  for (int i : order) {
    Stream st(s.seed ^ 0x5bd1e995ULL, static_cast<std::uint64_t>(i));
    bool placed = false;
    for (int attempt = 0; attempt < 100000 && !placed; ++attempt) {
      const double x = st.uniform(0, edge), y = st.uniform(0, edge), z = st.uniform(0, edge);
      const int cx = std::min(nc - 1, static_cast<int>(x / cl));
      const int cy = std::min(nc - 1, static_cast<int>(y / cl));
      const int cz = std::min(nc - 1, static_cast<int>(z / cl));
      bool ok = true;
      for (int dz = -1; dz <= 1 && ok; ++dz)
        for (int dy = -1; dy <= 1 && ok; ++dy)
          for (int dx = -1; dx <= 1 && ok; ++dx) {
            const int c =
                (((cz + dz + nc) % nc) * nc + (cy + dy + nc) % nc) * nc + (cx + dx + nc) % nc;
            for (int j : cells[c]) {
              const double rx = b.min_image(x - h.x[j], 0), ry = b.min_image(y - h.y[j], 1),
                           rz = b.min_image(z - h.z[j], 2);
              const double sum = h.radius[i] + h.radius[j];
              if (rx * rx + ry * ry + rz * rz < sum * sum) {
                ok = false;
                break;
              }
            }
          }  // with fewer than 3 cells per axis some cells are checked twice: harmless
      if (!ok) continue;
      h.x[i] = x, h.y[i] = y, h.z[i] = z;
      cells[(cz * nc + cy) * nc + cx].push_back(i);
      placed = true;
    }
    if (!placed)
      throw InputError("could not insert particle " + std::to_string(i) +
                       " without overlap at phi = " + std::to_string(s.phi) +
                       ": lower the gas volume fraction");
  }
  return h;
}

void check_gas(const SceneFile& scene, const GasSpec& g, const std::string& phi_key,
               const std::string& table) {
  const std::string dmin = table + ".diameter_min", dmax = table + ".diameter_max";
  scene.require(g.diameter_min > 0, dmin, "must be positive");
  scene.require(g.diameter_max >= g.diameter_min && g.diameter_max <= 100 * g.diameter_min, dmax,
                "must lie between " + dmin +
                    " and 100 times it (the neighbour grid is sized by the largest particle)");
  scene.require(g.density > 0, table + ".density", "must be positive");
  scene.require(g.speed >= 0, table + ".initial_speed", "must not be negative");
  scene.require(g.phi >= 1e-3 && g.phi <= kMaxGasFraction, phi_key,
                "must lie in [0.001, 0.45]: random insertion jams above");
  // The box edge (N V_max / phi)^(1/3) and its volume must stay finite.
  const double v_max = M_PI / 6 * g.diameter_max * g.diameter_max * g.diameter_max;
  scene.require(std::isfinite(v_max * g.count / g.phi), dmax,
                "is too large: the box volume overflows");
}

namespace {
bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}
}  // namespace

HostParticles read_packing_file(const std::string& path, double density, PeriodicBox& box,
                                const std::string& group) {
  HostParticles h;
  if (ends_with(path, ".h5md")) {
    const H5Reader in(path);
    const std::string p = "/particles/all";
    for (const char* item : {"/position/value", "/radius", "/box/edges/value"})
      if (!in.has(p + item)) throw InputError(path + ": no " + p + item + " (not an H5MD series)");
    const auto pos = in.reals(p + "/position/value"), radius = in.reals(p + "/radius");
    const auto edges = in.reals(p + "/box/edges/value");
    const size_t n = radius.size();
    if (n == 0 || pos.size() % (3 * n) != 0 || edges.size() % 9 != 0 ||
        edges.size() / 9 != pos.size() / (3 * n))
      throw InputError(path + ": position, radius and box/edges do not agree in size");
    const size_t last = pos.size() / (3 * n) - 1;  // the last frame
    h.resize(static_cast<int>(n));
    for (size_t i = 0; i < n; ++i) {
      const double* x = &pos[3 * (last * n + i)];
      h.x[i] = x[0], h.y[i] = x[1], h.z[i] = x[2];
      h.radius[i] = radius[i];
      h.density[i] = density;
    }
    if (in.has(p + "/species")) {
      const auto sp = in.ints(p + "/species");
      for (size_t i = 0; i < n && i < sp.size(); ++i) h.species[i] = sp[i];
    }
    const double* e = &edges[9 * last];
    if (e[1] != 0 || e[2] != 0 || e[3] != 0 || e[5] != 0 || e[6] != 0 || e[7] != 0)
      throw InputError(path + ": a triclinic box; the engine's periodic box is cuboid");
    for (int d = 0; d < 3; ++d) box.lo[d] = 0, box.len[d] = e[4 * d];
    // H5MD stores the edges only: positions are taken in a box at the origin, which the
    // periodic wrap makes the same packing.
  } else if (ends_with(path, ".h5")) {
    const H5Reader in(path);
    if (!in.has(group)) throw InputError(path + ": no state group " + group);
    double stored = 0;
    h = read_state(in, group, box, stored);
    for (double& r : h.density) r = density;
  } else {
    const LammpsData d = read_lammps_data(path);
    if (d.triclinic())
      throw InputError(path + ": a triclinic box; the engine's periodic box is cuboid");
    h = d.particles;
    for (int k = 0; k < 3; ++k) box.lo[k] = d.lo[k], box.len[k] = d.len[k];
  }
  if (h.size() < 2) throw InputError(path + ": fewer than 2 particles");
  return h;
}

}  // namespace granular

namespace granular {

void refuse_beside_packing(const SceneFile& scene, const std::vector<std::string>& keys,
                           const std::string& from_key, const std::string& gives) {
  for (const std::string& key : keys)
    scene.require(!scene.has(key), key,
                  "must not be given with " + from_key + " (the packing file gives " + gives + ")");
}

HostParticles read_scene_packing(const SceneFile& scene, const std::string& from_key,
                                 const std::string& path, const std::string& density_key,
                                 const std::string& group, PeriodicBox& box) {
  double density = 0;
  if (ends_with(path, ".h5") || ends_with(path, ".h5md")) {
    density = scene.real(density_key);
    scene.require(density > 0 && std::isfinite(density), density_key,
                  "must be positive and finite");
  }
  return read_scene_packing(scene, from_key, path, density, group, box);
}

HostParticles read_scene_packing(const SceneFile& scene, const std::string& from_key,
                                 const std::string& path, double density, const std::string& group,
                                 PeriodicBox& box) {
  try {
    return read_packing_file(path, density, box, group);
  } catch (const InputError& e) {
    scene.require(false, from_key, e.what());
    throw;  // require(false, ...) has thrown already
  }
}

}  // namespace granular
