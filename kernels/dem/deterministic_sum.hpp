// Reductions whose result does not depend on the thread count: values are summed in fixed
// blocks of consecutive indices (each block by one thread, in index order) and the block
// sums are then added on the host in block order. Used for every diagnostic (energies,
// stress, coordination) so runs with 1 and 2 threads print identical numbers.
#pragma once
#include <Kokkos_Core.hpp>
#include <array>
#include <string>

namespace granular {

// The block size is a constant, not a function of the number of threads, which is what
// makes the results reproducible.
constexpr int kDeterministicBlock = 256;

// Adds the column sums of the first n rows of a (rows x NC) View to `out`, block by block
// in index order. Calling it on consecutive chunks of a table (each a whole number of blocks
// but the last) gives the same bits as one call on the whole table.
template <int NC, class ExecSpace, class View2D>
void accumulate_deterministic_column_sums(const View2D& values, int n,
                                          std::array<double, NC>& out) {
  constexpr int block = kDeterministicBlock;
  const int nblocks = (n + block - 1) / block;
  using mem = typename ExecSpace::memory_space;
  Kokkos::View<double**, Kokkos::LayoutRight, mem> partial("reduce::partial", nblocks, NC);
  Kokkos::parallel_for(
      "reduce::deterministic::blocks", Kokkos::RangePolicy<ExecSpace>(0, nblocks),
      KOKKOS_LAMBDA(const int b) {
        const int begin = b * block;
        const int end = begin + block < n ? begin + block : n;
        for (int c = 0; c < NC; ++c) {
          double s = 0.0;
          for (int i = begin; i < end; ++i) s += values(i, c);
          partial(b, c) = s;
        }
      });
  auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), partial);
  for (int b = 0; b < nblocks; ++b)
    for (int c = 0; c < NC; ++c) out[c] += host(b, c);
}

// Sums columns of a (n x NC) View.
template <int NC, class ExecSpace, class View2D>
std::array<double, NC> deterministic_column_sums(const View2D& values, int n) {
  std::array<double, NC> out{};
  accumulate_deterministic_column_sums<NC, ExecSpace>(values, n, out);
  return out;
}

}  // namespace granular
