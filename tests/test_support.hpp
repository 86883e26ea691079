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

// Every scratch path handed out below, removed when the test binary ends (test_main.cpp) unless
// a test failed: then they are kept, and listed, for inspection.
inline std::vector<std::filesystem::path>& scratch_paths() {
  static std::vector<std::filesystem::path> paths;
  return paths;
}

inline std::filesystem::path unique_temp_path(const std::string& name) {
  const auto path = std::filesystem::temp_directory_path() /
                    (name + "_" + std::to_string(static_cast<long>(::getpid())));
  scratch_paths().push_back(path);
  return path;
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

// A small isotropic_compression scene (300 spheres, seconds) that checkpoints every 2000
// steps: the checkpoint, resume and run-report tests run it, some with keys added at the end
// of its [run] table (stop_after).
inline std::string small_isotropic_scene() {
  return R"(scene = "isotropic_compression"
[particles]
count = 300
diameter_min = 1.0
diameter_max = 3.0
density = 2000.0
seed = 4
initial_speed = 1.0e-3
[contact]
kn = 1.0e5
gamma_n = 1000.0
[damping]
background = 100.0
[compression]
phi_start = 0.4
phi_end = 0.62
volumetric_strain_rate = 2.0e-2
relax_steps = 500
[run]
dt = 0.004
skin = 0.2
sample_every = 250
checkpoint_every = 2000
)";
}

}  // namespace granular::testing
