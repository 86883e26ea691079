// Test entry point: Kokkos is initialized once per process with the command-line thread
// count (--kokkos-threads=N), so ctest can run every test with 1 and with 2 threads.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "tests/test_support.hpp"

namespace {
// The tests' scratch folders and files (unique_temp_path, temp_dir) go when the binary ends,
// so that runs do not pile them up in the temporary directory; a failed run keeps them.
class ScratchCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    auto& paths = granular::testing::scratch_paths();
    if (::testing::UnitTest::GetInstance()->Failed()) {
      for (const auto& p : paths)
        if (std::filesystem::exists(p)) std::cerr << "kept for inspection: " << p.string() << "\n";
      return;
    }
    for (const auto& p : paths) {
      std::error_code ignored;
      std::filesystem::remove_all(p, ignored);
    }
  }
};
}  // namespace

int main(int argc, char** argv) {
  // Listing (how ctest discovers the tests) needs no Kokkos: its OpenMP start-up warnings
  // would go to stdout and be read as test names.
  bool listing = false;
  for (int i = 1; i < argc; ++i)
    listing = listing || std::strcmp(argv[i], "--gtest_list_tests") == 0;
  ::testing::InitGoogleTest(&argc, argv);
  if (listing) return RUN_ALL_TESTS();
  ::testing::AddGlobalTestEnvironment(new ScratchCleanup);  // gtest owns and deletes it
  // Threads that are not pinned, as ctest sets it; a direct run gets the same default.
  setenv("OMP_PROC_BIND", "false", 0);
  Kokkos::initialize(argc, argv);
  const int rc = RUN_ALL_TESTS();
  Kokkos::finalize();
  return rc;
}
