// What each wall felt at the last force evaluation (force, torque about its point, contacts,
// elastic energy, largest overlap), kept for the wall sums (WallLoad) in a form whose sums do
// not depend on the thread count.
//
// The sums are those of kernels/dem/deterministic_sum.hpp: per block of kDeterministicBlock
// consecutive particles, in particle order, then the blocks in order. Two layouts give them:
//  - by blocks (host backends, systems of enough blocks: WallLayout): the wall pass visits
//    each block's particles in order in one thread and adds each contact's share to its
//    block's row of sums as it goes; nothing is stored per particle. A per-(particle, wall)
//    record would be 72 bytes a wall for every particle, most of which touch no wall (288
//    bytes a particle in the peer's walled box of two walls, docs/perf_design_notes.md, CPUs).
//  - by rows (devices, small systems, and the host on request): the pass runs one thread per
//    particle and writes each contact's share to the particle's row; the block sums are taken
//    from the rows when asked for.
// Both add the same numbers in the same order to a sum that starts at +0: a block's sum over
// its touching rows only is its sum over all rows, since adding +0 changes no sum that
// started at +0 (such a sum is never -0). The same bits either way (tests/kernels/dem/
// test_walls.cpp holds them to it).
#pragma once
#include <Kokkos_Core.hpp>
#include <type_traits>
#include <vector>

#include "kernels/dem/deterministic_sum.hpp"
#include "kernels/dem/permute_rows.hpp"

namespace granular {

// Columns of a wall contact's share: force on the wall (3), torque on the wall about its
// reference point (3), contact flag, elastic energy, overlap / a_i. In the block sums,
// column 8 holds the block's largest overlap instead of a sum.
constexpr int kWallColumns = 9;

// Whether a (particle, wall) contact stood at the last evaluation, one byte each: what the wall
// pass reads for every particle (a contact that has just ended clears its history, and its
// row where there are rows). Reading the flag from a row of 72 bytes stalled the pass on a
// cache miss per particle (a quarter of the step in a box of 32768 spheres between two walls).
template <class ExecSpace>
using WallTouchView =
    Kokkos::View<unsigned char**, Kokkos::LayoutRight, typename ExecSpace::memory_space>;

// What the walls feel, summed over particles in a fixed order (thread-count independent).
struct WallLoad {
  double force[3] = {};   // total force on the wall
  double torque[3] = {};  // about the wall's reference point
  double contacts = 0;
  double energy = 0;       // elastic energy stored in its contacts
  double max_overlap = 0;  // largest delta / a_i
};

// Where the wall pass puts a particle's contacts: its row of the record (RowSink) or the
// running sums of its block (BlockSink). contact(): the contact (i, w) stands with these
// kWallColumns numbers; ended(): it stood at the last evaluation and no longer does.
template <class ExecSpace>
struct WallRowSink {
  Kokkos::View<double**, Kokkos::LayoutRight, typename ExecSpace::memory_space> rows;
  WallTouchView<ExecSpace> touch;
  KOKKOS_INLINE_FUNCTION void contact(int i, int w, const double share[kWallColumns]) const {
    for (int c = 0; c < kWallColumns; ++c) rows(i, w * kWallColumns + c) = share[c];
    touch(i, w) = 1;
  }
  KOKKOS_INLINE_FUNCTION void ended(int i, int w) const {
    for (int c = 0; c < kWallColumns; ++c) rows(i, w * kWallColumns + c) = 0.0;
    touch(i, w) = 0;
  }
};

template <class ExecSpace>
struct WallBlockSink {
  double* sums;  // the block's row: kWallColumns per wall, zeroed before its first particle
  WallTouchView<ExecSpace> touch;
  KOKKOS_INLINE_FUNCTION void contact(int i, int w, const double share[kWallColumns]) const {
    double* s = sums + w * kWallColumns;
    for (int c = 0; c < kWallColumns - 1; ++c) s[c] += share[c];
    s[kWallColumns - 1] = share[kWallColumns - 1] > s[kWallColumns - 1] ? share[kWallColumns - 1]
                                                                        : s[kWallColumns - 1];
    touch(i, w) = 1;
  }
  KOKKOS_INLINE_FUNCTION void ended(int i, int w) const { touch(i, w) = 0; }
};

// Block sums of a record's rows. A functor class rather than a lambda: nvcc's wrapper of a
// host-device lambda inside a function template instantiated in several translation units can
// be linked with a null copy helper (docs/perf_design_notes.md, GPU).
template <class RowsView, class SumsView>
struct WallRowSumsPass {
  RowsView rows;
  SumsView sums;
  int n, columns;
  KOKKOS_INLINE_FUNCTION void operator()(const int b) const {
    const int begin = b * kDeterministicBlock;
    const int end = begin + kDeterministicBlock < n ? begin + kDeterministicBlock : n;
    for (int c = 0; c < columns; ++c) {
      double s = 0.0;
      if (c % kWallColumns == kWallColumns - 1)
        for (int i = begin; i < end; ++i) s = rows(i, c) > s ? rows(i, c) : s;
      else
        for (int i = begin; i < end; ++i) s += rows(i, c);
      sums(b, c) = s;
    }
  }
};

// Contact flags copied between the engine's bytes and the saved form's ints (a functor, as
// above).
template <class Dst, class Src>
struct WallFlagsPass {
  Dst dst;
  Src src;
  int nw;
  KOKKOS_INLINE_FUNCTION void operator()(const int i) const {
    for (int w = 0; w < nw; ++w) dst(i, w) = src(i, w) != 0 ? 1 : 0;
  }
};

// Which layout a system takes. Auto: by blocks on a host backend where each thread has at least
// kWallBlocksPerThread blocks to take, by rows otherwise (a box of 514 balls is three blocks:
// with two threads, one of them took two and the wall pass ran 1.6-2.1x slower than by rows).
// Blocks is honoured on host backends only; both give the same bits.
enum class WallLayout { Auto, Rows, Blocks };
constexpr int kWallBlocksPerThread = 4;

template <class ExecSpace>
class WallRecord {
 public:
  using mem = typename ExecSpace::memory_space;
  using sums_view = Kokkos::View<double**, Kokkos::LayoutRight, mem>;

  static constexpr bool host = std::is_same_v<mem, Kokkos::HostSpace>;

  // n particles, nw walls; everything zero (no contact stood before).
  void reset(int n, int nw, WallLayout layout) {
    n_ = nw > 0 ? n : 0, nw_ = nw;
    const bool enough = blocks() >= kWallBlocksPerThread * ExecSpace().concurrency();
    by_blocks_ = host && (layout == WallLayout::Blocks || (layout == WallLayout::Auto && enough));
    touch_ = WallTouchView<ExecSpace>("dem::wall_touch", n_, nw);
    rows_ = sums_view("dem::wall_record", by_blocks_ ? 0 : n_, by_blocks_ ? 0 : nw * kWallColumns);
    sums_ = sums_view("dem::wall_sums", blocks(), nw * kWallColumns);
    sums_current_ = by_blocks_;
  }
  bool by_blocks() const { return by_blocks_; }
  int walls() const { return nw_; }
  int blocks() const { return (n_ + kDeterministicBlock - 1) / kDeterministicBlock; }

  WallRowSink<ExecSpace> row_sink() const { return {rows_, touch_}; }
  const sums_view& block_sums_view() const { return sums_; }
  const WallTouchView<ExecSpace>& touch() const { return touch_; }
  // A force pass has written the rows (or the block sums).
  void evaluated() { sums_current_ = by_blocks_; }

  // Particles reordered (new i = old order(i)): the flags and rows follow them. Block sums
  // stay those of the last evaluation, in the order it summed them.
  template <class Order>
  void reorder(const Order& order, int n) {
    permute_rows<ExecSpace>(touch_, order, n);
    permute_rows<ExecSpace>(rows_, order, n);
  }

  // Each wall's load as of the last evaluation.
  std::vector<WallLoad> loads() const {
    std::vector<WallLoad> out(nw_);
    if (nw_ == 0) return out;
    auto sums = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), current_sums());
    for (int w = 0; w < nw_; ++w) {
      WallLoad& l = out[w];
      const int c0 = w * kWallColumns;
      for (int b = 0; b < static_cast<int>(sums.extent(0)); ++b) {
        for (int d = 0; d < 3; ++d)
          l.force[d] += sums(b, c0 + d), l.torque[d] += sums(b, c0 + 3 + d);
        l.contacts += sums(b, c0 + 6);
        l.energy += sums(b, c0 + 7);
        l.max_overlap = sums(b, c0 + 8) > l.max_overlap ? sums(b, c0 + 8) : l.max_overlap;
      }
    }
    return out;
  }

  // The saved form, the same for both layouts: the flags and the block sums (rows of
  // particles that touch are rewritten at the next evaluation, the others are zero).
  using saved_touch = Kokkos::View<int**, Kokkos::LayoutRight, mem>;
  struct Saved {
    saved_touch touch;
    sums_view sums;
  };
  Saved saved() const {
    Saved s;
    s.touch = saved_touch("dem::wall_touch", touch_.extent(0), touch_.extent(1));
    Kokkos::parallel_for(
        "dem::WallRecord::saved", Kokkos::RangePolicy<ExecSpace>(0, n_),
        WallFlagsPass<saved_touch, WallTouchView<ExecSpace>>{s.touch, touch_, nw_});
    s.sums = sums_view("dem::wall_sums", sums_.extent(0), sums_.extent(1));
    Kokkos::deep_copy(s.sums, current_sums());
    return s;
  }
  bool same_shape(const Saved& s) const {
    return s.touch.extent(0) == touch_.extent(0) && s.touch.extent(1) == touch_.extent(1) &&
           s.sums.extent(0) == sums_.extent(0) && s.sums.extent(1) == sums_.extent(1);
  }
  void restore(const Saved& s) {
    Kokkos::parallel_for(
        "dem::WallRecord::restore", Kokkos::RangePolicy<ExecSpace>(0, n_),
        WallFlagsPass<WallTouchView<ExecSpace>, saved_touch>{touch_, s.touch, nw_});
    Kokkos::deep_copy(rows_, 0.0);
    Kokkos::deep_copy(sums_, s.sums);
    sums_current_ = true;  // until the next evaluation writes the rows
  }

 private:
  // The block sums of the last evaluation: the stored ones, or those of the rows.
  sums_view current_sums() const {
    if (sums_current_) return sums_;
    Kokkos::parallel_for(
        "dem::wall_loads::blocks", Kokkos::RangePolicy<ExecSpace>(0, blocks()),
        WallRowSumsPass<sums_view, sums_view>{rows_, sums_, n_, nw_ * kWallColumns});
    return sums_;
  }

  int n_ = 0, nw_ = 0;
  bool by_blocks_ = true, sums_current_ = true;
  WallTouchView<ExecSpace> touch_;
  sums_view rows_, sums_;
};

}  // namespace granular
