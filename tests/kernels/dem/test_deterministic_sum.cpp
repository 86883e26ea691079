// kernels/dem/deterministic_sum.hpp: sums that do not depend on the thread count, and the
// chunked form the device's measurements use (a table of 1M rows at a time instead of one row
// per particle) giving the same bits as one table.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <cmath>
#include <random>

#include "kernels/dem/deterministic_sum.hpp"
#include "tests/exec_spaces.hpp"

namespace granular {
namespace {

template <class ExecSpace>
class DeterministicSum : public ::testing::Test {};
TYPED_TEST_SUITE(DeterministicSum, testing::ExecSpaces);

template <class ExecSpace>
Kokkos::View<double**, Kokkos::LayoutRight, typename ExecSpace::memory_space> random_table(
    int n, int first_row = 0) {
  Kokkos::View<double**, Kokkos::LayoutRight, typename ExecSpace::memory_space> t("table", n, 3);
  auto h = Kokkos::create_mirror_view(t);
  for (int i = 0; i < n; ++i) {
    // Each row from its own index, so a chunk's rows equal the whole table's.
    std::mt19937_64 rng(1000 + first_row + i);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int c = 0; c < 3; ++c) h(i, c) = std::ldexp(u(rng), 20 * c - 20);
  }
  Kokkos::deep_copy(t, h);
  return t;
}

TYPED_TEST(DeterministicSum, ChunksOfWholeBlocksGiveTheSameBitsAsOneTable) {
  using Exec = TypeParam;
  const int n = 7 * kDeterministicBlock + 91;  // a partial last block
  const auto whole = deterministic_column_sums<3, Exec>(random_table<Exec>(n), n);

  const int chunk = 2 * kDeterministicBlock;
  std::array<double, 3> chunked{};
  for (int begin = 0; begin < n; begin += chunk) {
    const int len = std::min(chunk, n - begin);
    accumulate_deterministic_column_sums<3, Exec>(random_table<Exec>(len, begin), len, chunked);
  }
  for (int c = 0; c < 3; ++c) EXPECT_EQ(chunked[c], whole[c]) << "column " << c;

  // And the sums are the sums: against a long-double sum of the same rows.
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), random_table<Exec>(n));
  for (int c = 0; c < 3; ++c) {
    long double s = 0, scale = 0;
    for (int i = 0; i < n; ++i) s += h(i, c), scale += std::fabs(h(i, c));
    EXPECT_NEAR(whole[c], static_cast<double>(s), 1e-14 * static_cast<double>(scale));
  }
}

}  // namespace
}  // namespace granular
