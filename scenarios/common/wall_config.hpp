// Walls and boundaries from a scene file, and what a walled run writes about its walls.
//
//   [boundary]  periodic = [1, 1, 0]      per axis: 1 periodic, 0 closed (by walls)
//   [walls.top] normal = [0, 0, 1]   point = [0, 0, 0.167]   material = "steel"
//               motion = "fixed" | "velocity" | "table"
//               velocity = [0, 0, -0.001]                      (motion = "velocity")
//               times = [0, 1, 2]  displacements = [0, -0.02, 0]   (motion = "table":
//               displacement along the outward normal, negative into the sample)
#pragma once
#include <map>
#include <string>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/walls.hpp"
#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"

namespace granular {

// Reads [walls.<name>] (sorted by name); `material_slot` maps a material name to its
// species slot (an unknown name is an error naming the key).
std::vector<WallSpec> read_walls(const SceneFile& scene,
                                 const std::map<std::string, int>& material_slot);

// Reads boundary.periodic into box.periodic; absent, every axis takes `default_periodic`.
void read_boundary(const SceneFile& scene, PeriodicBox& box, bool default_periodic);

// Time series of every wall, for results.h5: /walls/<name>/{time, position, force, torque,
// contacts} (position: the reference point; force and torque: on the wall).
struct WallSeries {
  std::vector<std::string> names;
  std::vector<double> time;
  std::vector<std::vector<double>> position, force, torque, contacts;  // per wall, flattened
  void resize(const std::vector<WallSpec>& walls);
  void write(H5Writer& out, const std::string& group = "/walls") const;
};

// The corners of the polygon where the plane of `w` at its current point cuts the box,
// reduced to a quad (the plane's extent inside the box along two in-plane directions).
std::vector<double> wall_quad(const double normal[3], const double point[3],
                              const PeriodicBox& box);

}  // namespace granular
