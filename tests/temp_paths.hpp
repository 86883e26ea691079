// Scratch paths of the tests. ctest runs every test twice (1 and 2 threads), possibly at
// the same time under -j: each process gets its own names, suffixed with its pid.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <string>

namespace granular::testing {

inline std::filesystem::path unique_temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         (name + "_" + std::to_string(static_cast<long>(::getpid())));
}

}  // namespace granular::testing
