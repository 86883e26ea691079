// Per-contact history (tangential spring, rolling/torsion springs, delta_max) stored next to
// the neighbour list it belongs to: slot k of the list owns row k. After a rebuild, each new
// slot (i, j) finds partner j among i's old partners by particle identity and inherits
// their history, or starts fresh; the history therefore survives rebuilds and periodic
// re-entry. Capacity follows the list exactly (count -> scan -> fill), so nothing overflows.
#pragma once
#include <Kokkos_Core.hpp>

#include "core/particles.hpp"
#include "kernels/neighbor_list.hpp"

namespace granular {

template <class ExecSpace, int H>
class ContactHistory {
 public:
  using mem = typename ExecSpace::memory_space;
  using values_view = Kokkos::View<double**, Kokkos::LayoutRight, mem>;
  using int_view = Kokkos::View<int*, mem>;

  const values_view& values() const { return values_; }

  // Carries history over from the list as it was (old_offsets/old_partner_ids) to the
  // list as it is now. Call right after every rebuild. `old_index(i)` is the index particle
  // i had before the particles were reordered (empty view: no reordering).
  void remap(const Particles<ExecSpace>& p, const NeighborList<ExecSpace>& nl,
             const int_view& old_index = int_view()) {
    if constexpr (H == 0) {
      return;
    } else {
      const int entries = nl.num_entries();
      values_view fresh("contact_history::values", entries > 0 ? entries : 1, H);
      int_view fresh_ids("contact_history::partner_id", entries > 0 ? entries : 1);
      auto offsets = nl.offsets(), neighbors = nl.neighbors();
      auto id = p.id;
      auto old_values = values_;
      auto old_offsets = offsets_, old_ids = partner_ids_;
      const bool have_old = old_offsets.extent(0) == static_cast<size_t>(p.n + 1);
      const bool reordered = old_index.extent(0) == static_cast<size_t>(p.n);
      Kokkos::parallel_for(
          "contact_history::ContactHistory::remap", Kokkos::RangePolicy<ExecSpace>(0, p.n),
          KOKKOS_LAMBDA(const int i) {
            for (int k = offsets(i); k < offsets(i + 1); ++k) {
              const int pid = id(neighbors(k));
              fresh_ids(k) = pid;
              int found = -1;
              const int oi = reordered ? old_index(i) : i;
              if (have_old)
                for (int o = old_offsets(oi); o < old_offsets(oi + 1); ++o)
                  if (old_ids(o) == pid) {
                    found = o;
                    break;
                  }
              for (int c = 0; c < H; ++c) fresh(k, c) = found >= 0 ? old_values(found, c) : 0.0;
            }
          });
      values_ = fresh;
      partner_ids_ = fresh_ids;
      offsets_ = int_view("contact_history::offsets", p.n + 1);
      Kokkos::deep_copy(offsets_, offsets);
    }
  }

  // For exact restarts (see NeighborList::save).
  void save(H5Writer& out, const std::string& g) const {
    if constexpr (H > 0) {
      save_view(out, g + "/values", values_);
      save_view(out, g + "/partner_ids", partner_ids_);
      save_view(out, g + "/offsets", offsets_);
    }
  }
  void load(const H5Reader& in, const std::string& g) {
    if constexpr (H > 0) {
      load_view(in, g + "/values", values_);
      load_view(in, g + "/partner_ids", partner_ids_);
      load_view(in, g + "/offsets", offsets_);
    }
  }

 private:
  values_view values_;
  int_view partner_ids_, offsets_;
};

}  // namespace granular
