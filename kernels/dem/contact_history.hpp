// Per-contact history (tangential spring, rolling/torsion springs, delta_max) stored next to
// the neighbour list it belongs to. After a rebuild, each new row (i, j) finds partner j
// among i's old partners by particle identity and inherits their history, or starts fresh;
// the history therefore survives rebuilds and periodic re-entry. Capacity follows the list
// exactly (count -> scan -> fill), so nothing overflows.
//
// Two layouts. Owner rows (OwnerRows = true, the contact laws' history): only the owner of
// a contact (lower identity) evaluates it, so only owned entries have a row, row
// NeighborList::pair_begin(i) + k - offsets(i) for owned entry k of particle i: half the
// memory and traffic of one row per list entry. Entry rows (false): row k for list entry k,
// for per-entry data that the non-owned side reads as well.
#pragma once
#include <Kokkos_Core.hpp>
#include <string>
#include <vector>

#include "core/dem/particles.hpp"
#include "core/run/error.hpp"
#include "kernels/dem/neighbor_list.hpp"

namespace granular {

template <class ExecSpace, int H, bool OwnerRows = false>
class ContactHistory {
 public:
  using mem = typename ExecSpace::memory_space;
  using values_view = Kokkos::View<double**, Kokkos::LayoutRight, mem>;
  using int_view = Kokkos::View<int*, mem>;

  const values_view& values() const { return values_; }

  // Carries history over from the list as it was (begin_/partner_ids_) to the list as it is
  // now. Call right after every rebuild. `old_index(i)` is the index particle i had before
  // the particles were reordered (empty view: no reordering).
  void remap(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
             const int_view& old_index = int_view()) {
    if constexpr (H == 0) {
      return;
    } else {
      const int rows = OwnerRows ? nl.num_pairs() : nl.num_entries();
      values_view fresh(Kokkos::view_alloc("contact_history::values", Kokkos::WithoutInitializing),
                        rows > 0 ? rows : 1, H);
      int_view fresh_ids(
          Kokkos::view_alloc("contact_history::partner_id", Kokkos::WithoutInitializing),
          rows > 0 ? rows : 1);
      auto offsets = nl.offsets(), neighbors = nl.neighbors();
      auto row_begin = OwnerRows ? nl.pair_begin() : nl.offsets();
      auto entries_end = OwnerRows ? nl.owned_end() : int_view();
      auto id = p.id;
      auto old_values = values_;
      auto old_begin = begin_, old_ids = partner_ids_;
      const bool have_old = old_begin.extent(0) == static_cast<size_t>(p.n + 1);
      const bool reordered = old_index.extent(0) == static_cast<size_t>(p.n);
      Kokkos::parallel_for(
          "contact_history::ContactHistory::remap", Kokkos::RangePolicy<ExecSpace>(0, p.n),
          KOKKOS_LAMBDA(const int i) {
            const int k0 = offsets(i), k1 = OwnerRows ? entries_end(i) : offsets(i + 1);
            const int oi = reordered ? old_index(i) : i;
            for (int k = k0; k < k1; ++k) {
              const int row = row_begin(i) + (k - k0);
              const int pid = id(neighbors(k));
              fresh_ids(row) = pid;
              int found = -1;
              if (have_old)
                for (int o = old_begin(oi); o < old_begin(oi + 1); ++o)
                  if (old_ids(o) == pid) {
                    found = o;
                    break;
                  }
              for (int c = 0; c < H; ++c) fresh(row, c) = found >= 0 ? old_values(found, c) : 0.0;
            }
          });
      values_ = fresh;
      partner_ids_ = fresh_ids;
      if (begin_.extent(0) != static_cast<size_t>(p.n + 1))
        begin_ = int_view("contact_history::begin", p.n + 1);
      Kokkos::deep_copy(begin_, row_begin);
    }
  }

  static constexpr int columns = H;
  static constexpr bool owner_rows = OwnerRows;

  // For exact restarts (see NeighborList::Saved). `owner_rows` says the rows are one per
  // owned contact; restarts written before that layout have one row per list entry.
  struct Saved {
    values_view values;
    int_view partner_ids, offsets;
    bool owner_rows = OwnerRows;
  };
  Saved saved() const { return Saved{values_, partner_ids_, begin_, OwnerRows}; }
  // `nl` must be the list restored from the same restart. Entry rows are converted: the
  // owned entries' rows are kept.
  void restore(const Saved& s, const NeighborList<ExecSpace>& nl, const std::string& origin) {
    if constexpr (H > 0) {
      values_ = s.values, partner_ids_ = s.partner_ids, begin_ = s.offsets;
      const bool entry_rows = !OwnerRows || !s.owner_rows;
      const int rows = entry_rows ? nl.num_entries() : nl.num_pairs();
      const size_t expect = static_cast<size_t>(rows > 0 ? rows : 1);
      if (values_.extent(0) != expect || values_.extent(1) != static_cast<size_t>(H) ||
          partner_ids_.extent(0) != expect || begin_.extent(0) != nl.offsets().extent(0))
        throw InputError(origin + " has a contact history of " + std::to_string(values_.extent(0)) +
                         " rows for a list that needs " + std::to_string(rows));
      if (OwnerRows && entry_rows) to_owner_rows(nl);
    }
  }

  // Public only because nvcc rejects extended lambdas in private member functions.
  void to_owner_rows(const NeighborList<ExecSpace>& nl) {
    const int n = static_cast<int>(nl.owned_end().extent(0));
    const int rows = nl.num_pairs();
    values_view owner_values("contact_history::values", rows > 0 ? rows : 1, H);
    int_view ids("contact_history::partner_id", rows > 0 ? rows : 1);
    auto offsets = nl.offsets(), owned_end = nl.owned_end(), pair_begin = nl.pair_begin();
    auto old_values = values_;
    auto old_ids = partner_ids_;
    Kokkos::parallel_for(
        "contact_history::ContactHistory::to_owner_rows", Kokkos::RangePolicy<ExecSpace>(0, n),
        KOKKOS_LAMBDA(const int i) {
          for (int k = offsets(i); k < owned_end(i); ++k) {
            const int row = pair_begin(i) + (k - offsets(i));
            ids(row) = old_ids(k);
            for (int c = 0; c < H; ++c) owner_values(row, c) = old_values(k, c);
          }
        });
    values_ = owner_values;
    partner_ids_ = ids;
    begin_ = int_view("contact_history::begin", n + 1);
    Kokkos::deep_copy(begin_, pair_begin);
  }

 private:
  values_view values_;
  // partner_ids_(row): identity of the row's partner; begin_: each particle's first row
  // (n + 1), as the list had them when the rows were made.
  int_view partner_ids_, begin_;
};

}  // namespace granular
