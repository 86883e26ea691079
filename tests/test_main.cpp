// Test entry point: Kokkos is initialized once per process with the command-line thread
// count (--kokkos-threads=N), so ctest can run every test with 1 and with 2 threads.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  Kokkos::initialize(argc, argv);
  const int rc = RUN_ALL_TESTS();
  Kokkos::finalize();
  return rc;
}
