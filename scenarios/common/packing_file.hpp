// A starting packing named by a scene key (read_packing_file), with the two scene-side rules
// every scene that takes one shares: H5MD frames and state groups hold no density, so
// `density_key` gives it (LAMMPS data files carry their own), and a file that cannot be read
// is refused naming `from_key`. The second form takes the density from the scene's material
// instead of a key (`density` applies to H5MD and state groups only, as above).
#pragma once
#include <string>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/host_particles.hpp"
#include "core/io/scene_file.hpp"

namespace granular {

HostParticles read_scene_packing(const SceneFile& scene, const std::string& from_key,
                                 const std::string& path, const std::string& density_key,
                                 const std::string& group, PeriodicBox& box);
// Refuses each of `keys` (the ones that would draw the particles) where the scene gives a
// packing file under `from_key`, saying what the file gives instead (`gives`).
void refuse_beside_packing(const SceneFile& scene, const std::vector<std::string>& keys,
                           const std::string& from_key, const std::string& gives);

HostParticles read_scene_packing(const SceneFile& scene, const std::string& from_key,
                                 const std::string& path, double density, const std::string& group,
                                 PeriodicBox& box);

}  // namespace granular
