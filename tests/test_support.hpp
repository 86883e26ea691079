// What many tests share: their scratch paths, the text of shipped scene files and a bitwise
// comparison of arrays of doubles. ctest runs every test twice (1 and 2 threads), possibly at
// the same time under -j, so each process gets its own scratch names, suffixed with its pid.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "granular_config.hpp"

namespace granular::testing {

inline std::filesystem::path unique_temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         (name + "_" + std::to_string(static_cast<long>(::getpid())));
}

// A fresh (removed) scratch directory name for one test of this process.
inline std::string temp_dir(const std::string& name) {
  const auto dir = unique_temp_path("granular_test_" + name);
  std::filesystem::remove_all(dir);
  return dir.string();
}

// The whole text of a file ("" when it cannot be read).
inline std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Every shipped scene file: the *.toml of the family folders scenarios/<family>/.
inline std::vector<std::filesystem::path> shipped_scene_files() {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& family : fs::directory_iterator(fs::path(GRANULAR_SOURCE_DIR) / "scenarios")) {
    if (!family.is_directory()) continue;
    for (const auto& e : fs::directory_iterator(family.path()))
      if (e.path().extension() == ".toml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// The path of the shipped file scenarios/<family>/<name>, whichever family holds it ("" when
// none does, so that the caller's load fails naming the file).
inline std::string shipped_scene_path(const std::string& name) {
  namespace fs = std::filesystem;
  for (const auto& family : fs::directory_iterator(fs::path(GRANULAR_SOURCE_DIR) / "scenarios"))
    if (family.is_directory() && fs::exists(family.path() / name))
      return (family.path() / name).string();
  return std::string(GRANULAR_SOURCE_DIR) + "/scenarios/" + name;
}

// The text of a shipped scene file.
inline std::string shipped_scene(const std::string& name) {
  return read_text(shipped_scene_path(name));
}

// Replaces the first occurrence of `from` in `text` (a mutated scene file); a test whose
// anchor is gone fails instead of silently running the unmutated scene.
inline void replace_once(std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

// Whether two arrays hold the same bits (operator== would take -0 for +0 and fail on NaN).
inline bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  // Empty vectors (no spins in frictionless models) may hold a null pointer, which memcmp
  // must not receive even for zero bytes.
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

}  // namespace granular::testing
