// What many tests share: their scratch paths and the text of shipped scene files. ctest
// runs every test twice (1 and 2 threads), possibly at the same time under -j, so each
// process gets its own scratch names, suffixed with its pid.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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

// The text of scenarios/<name> in the source tree.
inline std::string shipped_scene(const std::string& name) {
  return read_text(std::string(GRANULAR_SOURCE_DIR) + "/scenarios/" + name);
}

// Replaces the first occurrence of `from` in `text` (a mutated scene file); a test whose
// anchor is gone fails instead of silently running the unmutated scene.
inline void replace_once(std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

}  // namespace granular::testing
