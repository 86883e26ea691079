// Test entry point: Kokkos is initialized once per process with the command-line thread
// count (--kokkos-threads=N), so ctest can run every test with 1 and with 2 threads.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <cstdlib>
#include <cstring>

int main(int argc, char** argv) {
  // Listing (how ctest discovers the tests) needs no Kokkos: its OpenMP start-up warnings
  // would go to stdout and be read as test names.
  bool listing = false;
  for (int i = 1; i < argc; ++i)
    listing = listing || std::strcmp(argv[i], "--gtest_list_tests") == 0;
  ::testing::InitGoogleTest(&argc, argv);
  if (listing) return RUN_ALL_TESTS();
  // Threads that are not pinned, as ctest sets it; a direct run gets the same default.
  setenv("OMP_PROC_BIND", "false", 0);
  Kokkos::initialize(argc, argv);
  const int rc = RUN_ALL_TESTS();
  Kokkos::finalize();
  return rc;
}
