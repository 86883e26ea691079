// `granular keys` (see scene_keys.hpp).
#include "scenarios/common/scene_keys.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "granular_config.hpp"
#include "scenarios/common/key_units.hpp"

namespace granular {

namespace {

// key -> the comment the file writes at the end of its line, or else the block of comment
// lines right above it.
std::map<std::string, std::string> key_comments(const std::string& path) {
  std::map<std::string, std::string> out;
  std::ifstream f(path);
  const std::regex table(R"(^\s*\[([A-Za-z0-9_.]+)\]\s*(#.*)?$)");
  const std::regex entry(R"(^\s*([A-Za-z0-9_]+)\s*=[^#]*(#\s*(.*))?$)");
  const std::regex comment(R"(^\s*#\s*(.*)$)");
  std::string line, prefix, above;
  std::smatch m;
  while (std::getline(f, line)) {
    if (std::regex_match(line, m, table)) {
      prefix = m[1].str() + ".";
      above.clear();
    } else if (std::regex_match(line, m, entry)) {
      const std::string trailing = m[3].str();
      out[prefix + m[1].str()] = trailing.empty() ? above : trailing;
      above.clear();
    } else if (std::regex_match(line, m, comment)) {
      above += (above.empty() ? "" : " ") + m[1].str();
    } else {
      above.clear();
    }
  }
  return out;
}

}  // namespace

std::vector<std::string> shipped_scene_files(const std::string& name) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  const fs::path root = fs::path(GRANULAR_SOURCE_DIR) / "scenarios";
  std::error_code ec;
  for (fs::recursive_directory_iterator it(root, ec), end; it != end && !ec; it.increment(ec)) {
    const fs::path& p = it->path();
    if (p.extension() != ".toml" || p.filename().string().front() == '.') continue;
    if (p.string().find("/reference/") != std::string::npos) continue;
    try {
      if (SceneFile::load(p.string()).text("scene", "") == name) out.push_back(p.string());
    } catch (const InputError&) {
      // not a scene file of this engine
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

SceneKeys scene_keys(const std::string& scene) {
  SceneKeys out;
  out.scene = scene;
  if (std::filesystem::is_regular_file(scene)) {
    out.files = {scene};
    out.scene = SceneFile::load(scene).text("scene", "");
  } else {
    out.files = shipped_scene_files(scene);
  }
  if (out.files.empty()) {
    std::string known;
    for (const SceneEntry& e : scene_registry())
      known += std::string(known.empty() ? "" : ", ") + e.name;
    throw InputError("no scene file or shipped scene named '" + scene + "' (scenes: " + known +
                     ")");
  }
  for (const std::string& path : out.files) {
    const SceneFile file = SceneFile::load(path);
    const SceneEntry& entry = find_scene(file);
    RunOptions opts;
    opts.check_only = true;
    opts.progress = false;
    entry.run(file, opts);  // reads and checks every key, runs nothing, writes nothing
    const auto comments = key_comments(path);
    for (const auto& [key, facts] : file.facts()) {
      if (key == "scene") continue;
      const bool fresh = !out.keys.count(key);
      KeyDoc& k = out.keys[key];
      if (fresh) {
        k.kind = facts.kind;
        k.required = !facts.has_default;
        k.default_value = facts.default_value;
        if (file.used().count(key)) k.example = file.used().at(key);
      }
      for (const std::string& r : facts.rules)
        if (std::find(k.rules.begin(), k.rules.end(), r) == k.rules.end()) k.rules.push_back(r);
      const auto c = comments.find(key);
      if (c != comments.end() && k.meaning.empty()) k.meaning = c->second;
    }
  }
  // A key that only a check names (never read for these files nor asked about, and no table
  // of keys: check_gas names <table>.initial_speed for every scene that draws a gas, the
  // impact scenes name the target's keys a wall target does not read) is not required by
  // them: listed as "default absent", as the keys a driver only asks about.
  for (auto& [key, doc] : out.keys) {
    const std::string prefix = key + ".";
    const auto next = out.keys.upper_bound(key);
    const bool table = next != out.keys.end() && next->first.compare(0, prefix.size(), prefix) == 0;
    if (doc.kind.empty() && doc.required && !table)
      doc.required = false, doc.default_value = "absent";
    const auto units = key_units_of(out.scene, key);
    if (!units.empty()) doc.unit = units.front()->unit, doc.unit_note = units.front()->note;
  }
  return out;
}

Json SceneKeys::json() const {
  Json j = Json::object(), f = Json::array(), k = Json::object();
  for (const std::string& p : files) f.push(p);
  for (const auto& [key, d] : keys) {
    Json e = Json::object(), rules = Json::array();
    for (const std::string& r : d.rules) rules.push(r);
    e["kind"] = d.kind;
    e["required"] = d.required;
    e["default"] = d.required ? Json() : Json(d.default_value);
    e["unit"] = d.unit.empty() ? Json() : Json(d.unit);
    e["unit_note"] = d.unit_note.empty() ? Json() : Json(d.unit_note);
    e["rules"] = rules;
    e["example"] = d.example.empty() ? Json() : Json(d.example);
    e["meaning"] = d.meaning;
    k[key] = e;
  }
  j["scene"] = scene;
  j["files"] = f;
  j["keys"] = k;
  return j;
}

std::string SceneKeys::table() const {
  std::ostringstream o;
  o << "scene " << scene << ": the keys its driver reads in";
  for (const std::string& p : files) o << "\n  " << p;
  o << "\n\n";
  for (const auto& [key, d] : keys) {
    o << key << "  (" << (d.kind.empty() ? std::string() : d.kind + ", ")
      << (d.required ? std::string("required") : "default " + d.default_value) << ")\n";
    if (!d.unit.empty())
      o << "    unit: " << d.unit
        << (!d.unit_note.empty() ? " (" + d.unit_note + ")"
            : d.unit == "1"      ? std::string(" (a pure number)")
                                 : "")
        << "\n";
    if (!d.meaning.empty()) o << "    " << d.meaning << "\n";
    for (const std::string& r : d.rules) o << "    " << r << "\n";
    if (!d.example.empty()) o << "    e.g. " << d.example << "\n";
  }
  return o.str();
}

}  // namespace granular
