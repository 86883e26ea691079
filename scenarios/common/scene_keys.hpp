// `granular keys <scene>`: every key a scene driver reads, learned by checking the shipped
// scene files of that driver (or a given file) in check mode: its kind, its default (or that
// it is required), the rules the driver checks on it, an example value and the comment the
// shipped file writes beside it, and the unit of every numeric key (key_units.hpp). Keys a
// driver reads only for choices no shipped file makes are not listed (a driver reads the keys
// of the contact law a file picks, not of all).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

// The shipped scene files (under the source tree's scenarios/) whose `scene` is `name`.
std::vector<std::string> shipped_scene_files(const std::string& name);

struct KeyDoc {
  std::string kind, default_value, example, meaning;
  std::string unit, unit_note;  // numeric keys: the declared unit, and its scale where it has one
  bool required = true;
  std::vector<std::string> rules;
};
struct SceneKeys {
  std::string scene;
  std::vector<std::string> files;
  std::map<std::string, KeyDoc> keys;
  // {"scene", "files", "keys": {key: {kind, required, default, unit, unit_note, rules, example,
  // meaning}}}
  Json json() const;
  std::string table() const;  // for a terminal
};

// The keys of the scene named `scene` (a driver name, or the path of a scene file). Throws
// InputError for an unknown scene.
SceneKeys scene_keys(const std::string& scene);

}  // namespace granular
