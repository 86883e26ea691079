// Strict TOML scene reader (see scene_file.hpp).
#include "core/io/scene_file.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#define TOML_EXCEPTIONS 1
#include <toml++/toml.h>

namespace granular {

struct SceneFile::Document {
  toml::table root;
};

namespace {
const toml::node* as_node(const void* p) { return static_cast<const toml::node*>(p); }

std::string format_real(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}
}  // namespace

SceneFile SceneFile::load(const std::string& path) {
  SceneFile s;
  s.path_ = path;
  try {
    s.doc_ = std::make_shared<Document>();
    s.doc_->root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << path << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
        << e.description();
    throw InputError(msg.str());
  }
  return s;
}

SceneFile SceneFile::parse(const std::string& text, const std::string& source_name) {
  SceneFile s;
  s.path_ = source_name;
  try {
    s.doc_ = std::make_shared<Document>();
    s.doc_->root = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    throw InputError(source_name + ": " + std::string(e.description()));
  }
  return s;
}

const void* SceneFile::find(const std::string& key) const { return doc_->root.at_path(key).node(); }

namespace {
// Edits (insertions, deletions, substitutions) that turn a into b.
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] != b[j - 1])});
      diag = up;
    }
  }
  return row[b.size()];
}

// The candidate nearest to `key` if it is near enough to be a misspelling of it: at most a
// quarter of the key's length in edits (at least 2), and no other candidate as near.
std::string nearest(const std::string& key, const std::vector<std::string>& candidates) {
  const size_t limit = std::max<size_t>(2, key.size() / 4);
  std::string best;
  size_t best_d = limit + 1;
  bool tie = false;
  for (const std::string& c : candidates) {
    if (c == key) continue;
    const size_t d = edit_distance(key, c);
    if (d < best_d)
      best = c, best_d = d, tie = false;
    else if (d == best_d)
      tie = true;
  }
  return tie ? std::string() : best;
}

// Every leaf key of a TOML table, dotted.
void leaf_keys(const toml::table& t, const std::string& prefix, std::vector<std::string>& out) {
  for (const auto& [k, node] : t) {
    const std::string key =
        prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (const toml::table* sub = node.as_table())
      leaf_keys(*sub, key, out);
    else
      out.push_back(key);
  }
}
}  // namespace

void SceneFile::fail(const std::string& key, const std::string& what) const {
  std::string hint;
  if (!find(key)) {  // a missing key: is one in the file a misspelling of it?
    std::vector<std::string> present;
    leaf_keys(doc_->root, "", present);
    present.erase(std::remove_if(present.begin(), present.end(),
                                 [&](const std::string& k) { return used_.count(k) > 0; }),
                  present.end());
    const std::string near = nearest(key, present);
    if (!near.empty()) hint = " (the file has '" + near + "': misspelt?)";
  }
  throw InputError("scene file " + path_ + ": key '" + key + "' " + what + hint);
}

void SceneFile::require(bool ok, const std::string& key, const std::string& what) const {
  auto& rules = facts_[key].rules;
  if (std::find(rules.begin(), rules.end(), what) == rules.end()) rules.push_back(what);
  if (!ok) fail(key, what);
}

void SceneFile::require_distinct(const std::string& key, const std::vector<double>& values) const {
  for (size_t a = 0; a < values.size(); ++a)
    for (size_t b = a + 1; b < values.size(); ++b)
      if (values[a] == values[b])
        fail(key, "lists " + format_real(values[a]) + " twice (entries " + std::to_string(a + 1) +
                      " and " + std::to_string(b + 1) + "); each entry names its own output");
}

namespace {
// MemAvailable of /proc/meminfo in bytes (what can be allocated without swapping); +inf
// where it cannot be read, so that the check never refuses a run for want of a reading.
double available_memory() {
  std::ifstream f("/proc/meminfo");
  std::string name;
  double kb = 0;
  std::string unit;
  while (f >> name >> kb >> unit)
    if (name == "MemAvailable:") return kb * 1024.0;
  return std::numeric_limits<double>::infinity();
}
}  // namespace

void SceneFile::require_memory(const std::string& key, double bytes) const {
  const double avail = available_memory();
  if (!(bytes <= avail)) {
    std::ostringstream m;
    m.precision(3);
    m << "asks for a run that needs about " << bytes / 1e9 << " GB, more than the " << avail / 1e9
      << " GB available: make it smaller";
    fail(key, m.str());
  }
}

int SceneFile::count(const std::string& key, long min, double bytes_each) const {
  const long n = integer(key);
  require(n >= min, key, "must be at least " + std::to_string(min));
  require(n <= std::numeric_limits<int>::max(), key,
          "must be at most " + std::to_string(std::numeric_limits<int>::max()));
  require_memory(key, static_cast<double>(n) * bytes_each);
  return static_cast<int>(n);
}

void SceneFile::note(const std::string& key, const std::string& value) const { used_[key] = value; }
void SceneFile::kind(const std::string& key, const char* k) const { facts_[key].kind = k; }
void SceneFile::offer(const std::string& key, const std::string& default_value) const {
  facts_[key].default_value = default_value;
  facts_[key].has_default = true;
}

bool SceneFile::has(const std::string& key) const {
  // A key a driver asks about is one it knows: `granular keys` lists it even where no shipped
  // file gives it, as optional (a reader that follows adds its kind and default).
  const auto [at, fresh] = facts_.try_emplace(key);
  if (fresh) at->second.default_value = "absent", at->second.has_default = true;
  return find(key) != nullptr;
}

std::vector<std::string> SceneFile::tables(const std::string& key) const {
  std::vector<std::string> out;
  const toml::node* n = as_node(find(key));
  if (!n) return out;
  const toml::table* t = n->as_table();
  if (!t) fail(key, "must be a table of named tables ([" + key + ".<name>])");
  for (const auto& [k, node] : *t) {
    if (!node.as_table())
      fail(key + "." + std::string(k.str()),
           "must be a table ([" + key + "." + std::string(k.str()) + "])");
    out.emplace_back(k.str());
  }
  return out;
}

double SceneFile::real_or_infinite(const std::string& key) const {
  kind(key, "number");
  const toml::node* n = as_node(find(key));
  if (!n) fail(key, "is missing (a number is required)");
  if (auto v = n->value<double>()) {  // integers convert too
    if (std::isnan(*v) || *v == -std::numeric_limits<double>::infinity())
      fail(key, "must be a number or inf (nan and -inf are not)");
    note(key, format_real(*v));
    return *v;
  }
  fail(key, "must be a number");
}

double SceneFile::real(const std::string& key) const {
  kind(key, "number");
  const toml::node* n = as_node(find(key));
  if (!n) fail(key, "is missing (a number is required)");
  if (auto v = n->value<double>()) {  // integers convert too
    if (!std::isfinite(*v)) fail(key, "must be a finite number");
    note(key, format_real(*v));
    return *v;
  }
  fail(key, "must be a number");
}

long SceneFile::integer(const std::string& key) const {
  kind(key, "integer");
  const toml::node* n = as_node(find(key));
  if (!n) fail(key, "is missing (an integer is required)");
  if (auto v = n->value_exact<int64_t>()) {
    note(key, std::to_string(*v));
    return static_cast<long>(*v);
  }
  fail(key, "must be an integer");
}

std::string SceneFile::text(const std::string& key) const {
  kind(key, "string");
  const toml::node* n = as_node(find(key));
  if (!n) fail(key, "is missing (a string is required)");
  if (auto v = n->value_exact<std::string>()) {
    note(key, "\"" + *v + "\"");
    return *v;
  }
  fail(key, "must be a string");
}

bool SceneFile::flag(const std::string& key) const {
  kind(key, "flag");
  const toml::node* n = as_node(find(key));
  if (!n) fail(key, "is missing (true or false is required)");
  if (auto v = n->value_exact<bool>()) {
    note(key, *v ? "true" : "false");
    return *v;
  }
  fail(key, "must be true or false");
}

std::vector<double> SceneFile::reals(const std::string& key) const {
  std::vector<double> out = reals_in_file(key);
  if (out.empty()) fail(key, "must not be empty");
  return out;
}

std::vector<double> SceneFile::reals_in_file(const std::string& key) const {
  kind(key, "numbers");
  const toml::node* n = as_node(find(key));
  if (!n) fail(key, "is missing (an array of numbers is required)");
  const toml::array* a = n->as_array();
  if (!a) fail(key, "must be an array of numbers");
  std::vector<double> out;
  std::string text = "[";
  for (const auto& e : *a) {
    auto v = e.value<double>();
    if (!v) fail(key, "must contain only numbers");
    if (!std::isfinite(*v)) fail(key, "must contain only finite numbers");
    out.push_back(*v);
    text += (out.size() > 1 ? ", " : "") + format_real(*v);
  }
  if (!out.empty()) note(key, text + "]");  // an empty list is noted by the caller that allows it
  return out;
}

std::vector<std::string> SceneFile::texts(const std::string& key) const {
  kind(key, "strings");
  const toml::node* n = as_node(find(key));
  if (!n) fail(key, "is missing (an array of strings is required)");
  const toml::array* a = n->as_array();
  if (!a) fail(key, "must be an array of strings");
  std::vector<std::string> out;
  std::string text = "[";
  for (const auto& e : *a) {
    auto v = e.value_exact<std::string>();
    if (!v) fail(key, "must contain only strings");
    out.push_back(*v);
    std::string quoted;
    for (char c : *v) quoted += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
    text += (out.size() > 1 ? ", \"" : "\"") + quoted + "\"";
  }
  if (out.empty()) fail(key, "must not be empty");
  note(key, text + "]");
  return out;
}

double SceneFile::real(const std::string& key, double def) const {
  offer(key, format_real(def));
  kind(key, "number");
  if (find(key)) return real(key);
  note(key, format_real(def));
  return def;
}
int SceneFile::small_integer(const std::string& key) const {
  const long v = integer(key);
  if (v > std::numeric_limits<int>::max() || v < std::numeric_limits<int>::min())
    fail(key, "must lie within +-" + std::to_string(std::numeric_limits<int>::max()));
  return static_cast<int>(v);
}
int SceneFile::small_integer(const std::string& key, int def) const {
  offer(key, std::to_string(def));
  kind(key, "integer");
  if (find(key)) return small_integer(key);
  note(key, std::to_string(def));
  return def;
}
long SceneFile::integer(const std::string& key, long def) const {
  offer(key, std::to_string(def));
  kind(key, "integer");
  if (find(key)) return integer(key);
  note(key, std::to_string(def));
  return def;
}
std::string SceneFile::text(const std::string& key, const std::string& def) const {
  offer(key, "\"" + def + "\"");
  kind(key, "string");
  if (find(key)) return text(key);
  note(key, "\"" + def + "\"");
  return def;
}
std::string SceneFile::input_path(const std::string& key, bool folder) const {
  namespace fs = std::filesystem;
  const std::string given = text(key);
  require(!given.empty(), key, "is empty (a path is required)");
  fs::path p(given);
  if (p.is_relative()) p = fs::path(path_).parent_path() / p;
  const std::string resolved = p.lexically_normal().string();
  std::error_code ec;
  const bool is_folder = fs::is_directory(p, ec), is_file = fs::is_regular_file(p, ec);
  const std::string shown =
      "'" + given + "'" +
      (resolved != given
           ? " (" + resolved + ", relative paths are taken from the scene file's folder)"
           : "");
  if (folder && !is_folder)
    fail(key, "names " + shown +
                  (is_file ? ", a file where a folder is needed" : ", which does not exist"));
  if (!folder && !is_file)
    fail(key, "names " + shown +
                  (is_folder ? ", a folder where a file is needed" : ", which does not exist"));
  return resolved;
}
std::string SceneFile::optional_input_path(const std::string& key, bool folder) const {
  offer(key, "\"\"");
  kind(key, "string");
  if (find(key)) return input_path(key, folder);
  note(key, "\"\"");
  return std::string();
}
bool SceneFile::flag(const std::string& key, bool def) const {
  offer(key, def ? "true" : "false");
  kind(key, "flag");
  if (find(key)) return flag(key);
  note(key, def ? "true" : "false");
  return def;
}
std::vector<double> SceneFile::reals(const std::string& key, const std::vector<double>& def) const {
  return reals_with_default(key, def, false);
}
std::vector<double> SceneFile::reals_or_none(const std::string& key,
                                             const std::vector<double>& def) const {
  return reals_with_default(key, def, true);
}
std::vector<double> SceneFile::reals_with_default(const std::string& key,
                                                  const std::vector<double>& def,
                                                  bool may_be_empty) const {
  std::string text = "[";
  for (size_t i = 0; i < def.size(); ++i) text += (i ? ", " : "") + format_real(def[i]);
  offer(key, text + "]");
  kind(key, "numbers");
  if (find(key)) {
    if (!may_be_empty) return reals(key);
    const std::vector<double> out = reals_in_file(key);
    if (out.empty()) note(key, "[]");
    return out;
  }
  note(key, text + "]");
  return def;
}

void SceneFile::reject_unknown_keys() const {
  // Walk every leaf of the file; a leaf (or a whole table) that no reader touched is unknown.
  std::vector<std::pair<std::string, const toml::table*>> stack{{"", &doc_->root}};
  while (!stack.empty()) {
    auto [prefix, table] = stack.back();
    stack.pop_back();
    for (const auto& [k, node] : *table) {
      const std::string key =
          prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
      if (const toml::table* sub = node.as_table()) {
        stack.emplace_back(key, sub);
      } else if (!used_.count(key)) {
        std::vector<std::string> known;
        for (const auto& u : used_) known.push_back(u.first);
        const std::string near = nearest(key, known);
        throw InputError("scene file " + path_ + ": unknown key '" + key + "' (" +
                         (near.empty() ? std::string("misspelt, or not used by this scene")
                                       : "did you mean '" + near + "'?") +
                         ")");
      }
    }
  }
}

}  // namespace granular
