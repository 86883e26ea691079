// Table of scene drivers known to the CLI.
#include "scenarios/scene_registry.hpp"

namespace granular {

const std::vector<SceneEntry>& scene_registry() {
  static const std::vector<SceneEntry> entries = {
      // DEM scenes
      // chain scenes
  };
  return entries;
}

}  // namespace granular
