// Walls from scene files, wall time series and the XDMF view of particles and walls.
#include "scenarios/common/wall_config.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "core/io/dataset_units.hpp"

namespace granular {

namespace {
std::array<double, 3> vec3(const SceneFile& s, const std::string& key) {
  const auto v = s.reals(key);
  s.require(v.size() == 3, key, "must have three components");
  return {v[0], v[1], v[2]};
}
}  // namespace

std::vector<WallSpec> read_walls(const SceneFile& s,
                                 const std::map<std::string, int>& material_slot) {
  std::vector<WallSpec> out;
  for (const std::string& name : s.tables("walls")) {
    const std::string k = "walls." + name;
    WallSpec w;
    w.name = name;
    const auto n = vec3(s, k + ".normal"), p = vec3(s, k + ".point");
    for (int d = 0; d < 3; ++d) w.normal[d] = n[d], w.point[d] = p[d];
    const std::string material = s.text(k + ".material");
    const auto it = material_slot.find(material);
    s.require(it != material_slot.end(), k + ".material",
              "names no material of [materials] (\"" + material + "\")");
    w.material = it->second;
    const std::string motion = s.text(k + ".motion", "fixed");
    if (motion == "fixed") {
      w.motion = WallMotion::Fixed;
    } else if (motion == "velocity") {
      w.motion = WallMotion::Velocity;
      const auto v = vec3(s, k + ".velocity");
      for (int d = 0; d < 3; ++d) w.velocity[d] = v[d];
    } else if (motion == "table") {
      w.motion = WallMotion::Table;
      w.table_t = s.reals(k + ".times");
      w.table_u = s.reals(k + ".displacements");
    } else {
      s.require(false, k + ".motion", "must be \"fixed\", \"velocity\" or \"table\"");
    }
    try {
      w.validate(k);
    } catch (const InputError& e) {
      throw InputError("scene file " + s.path() + ": " + e.what());
    }
    out.push_back(w);
  }
  return out;
}

void read_boundary(const SceneFile& s, PeriodicBox& box, bool default_periodic) {
  const std::vector<double> def(3, default_periodic ? 1.0 : 0.0);
  if (!s.has("boundary.periodic")) {
    for (int d = 0; d < 3; ++d) box.periodic[d] = default_periodic;
    s.reals("boundary.periodic", def);  // records the default
    return;
  }
  const std::string key = "boundary.periodic";
  const auto v = s.reals(key);
  s.require(v.size() == 3, key, "must have three entries (1: periodic, 0: closed by walls)");
  for (int d = 0; d < 3; ++d) {
    s.require(v[d] == 0.0 || v[d] == 1.0, key, "entries must be 0 (walls) or 1 (periodic)");
    box.periodic[d] = v[d] == 1.0;
  }
}

void WallSeries::resize(const std::vector<WallSpec>& walls) {
  names.clear();
  for (const auto& w : walls) names.push_back(w.name);
  position.assign(walls.size(), {});
  force.assign(walls.size(), {});
  torque.assign(walls.size(), {});
  contacts.assign(walls.size(), {});
}

void WallSeries::write(H5Writer& out, const std::string& group) const {
  const hsize_t nt = time.size();
  for (size_t w = 0; w < names.size(); ++w) {
    const std::string g = group + "/" + names[w];
    write_quantity(out, g + "/time", time, "us");
    write_quantity(out, g + "/position", position[w], "mm", {nt, 3});
    write_quantity(out, g + "/force", force[w], "N", {nt, 3});
    write_quantity(out, g + "/torque", torque[w], "N mm", {nt, 3});  // about the wall's point
    write_quantity(out, g + "/contacts", contacts[w], "1");
  }
}

std::vector<double> wall_quad(const double n[3], const double p[3], const PeriodicBox& box) {
  // Two in-plane directions: e1 perpendicular to n and to the axis n is most aligned with.
  int a = 0;
  for (int d = 1; d < 3; ++d)
    if (std::fabs(n[d]) > std::fabs(n[a])) a = d;
  double helper[3] = {0, 0, 0};
  helper[(a + 1) % 3] = 1.0;
  double e1[3] = {n[1] * helper[2] - n[2] * helper[1], n[2] * helper[0] - n[0] * helper[2],
                  n[0] * helper[1] - n[1] * helper[0]};
  const double l1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (double& c : e1) c /= l1;
  const double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2],
                        n[0] * e1[1] - n[1] * e1[0]};
  // Extent of the box's corners projected on e1, e2 (about p): the quad covers the cut.
  double lo1 = 1e300, hi1 = -1e300, lo2 = 1e300, hi2 = -1e300;
  for (int c = 0; c < 8; ++c) {
    double r[3];
    for (int d = 0; d < 3; ++d) r[d] = box.lo[d] + ((c >> d) & 1) * box.len[d] - p[d];
    const double s1 = r[0] * e1[0] + r[1] * e1[1] + r[2] * e1[2];
    const double s2 = r[0] * e2[0] + r[1] * e2[1] + r[2] * e2[2];
    lo1 = std::min(lo1, s1), hi1 = std::max(hi1, s1), lo2 = std::min(lo2, s2),
    hi2 = std::max(hi2, s2);
  }
  std::vector<double> q;
  const double corners[4][2] = {{lo1, lo2}, {hi1, lo2}, {hi1, hi2}, {lo1, hi2}};
  for (const auto& c : corners)
    for (int d = 0; d < 3; ++d) q.push_back(p[d] + c[0] * e1[d] + c[1] * e2[d]);
  return q;
}

}  // namespace granular
