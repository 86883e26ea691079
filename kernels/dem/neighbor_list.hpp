// Linked-cell binning and a size-aware Verlet neighbour list with a skin (full list, CSR).
//
// Full list (each pair stored for both particles) so that every particle sums its own
// forces in a fixed order: no atomics, and results that are bitwise identical for any
// thread count and on any backend. Each contact is computed once, by its owner (the lower
// identity); the device's two passes gather it for both from the owner's row (pair_row), the
// host's one pass adds it to both at once. Per-contact data lives in the owners' rows only
// (pair_begin). The order inside a cell is sorted by particle identity for the same reason.
//
// The list is rebuilt only when it may have become wrong: some particle moved more than
// half the skin since the build, counting both its own motion and the affine shrinking of
// the box (a compressed box brings distant pairs closer without moving them "relative to
// the box").
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "core/run/error.hpp"
#include "kernels/cpu/force_slabs.hpp"
#include "kernels/cpu/neighbor_sweep.hpp"

namespace granular {

// Visits every j within a_i + a_j + skin of particle i, in a fixed order (cell offsets in
// z, y, x order, then index order inside each cell). A functor rather than a lambda so it
// is callable from device code with a generic callback.
template <class ExecSpace>
struct CellVisitor {
  using mem = typename ExecSpace::memory_space;
  Kokkos::View<double* [3], mem> x;
  Kokkos::View<double*, mem> radius;
  Kokkos::View<int*, mem> cell_of, cell_start, cell_particles;
  Kokkos::View<int*, mem> cell_rank;  // z-y-x cell index -> position in the cell order
  PeriodicBox box;
  double skin;
  int ncx, ncy, ncz;
  double a_max;  // largest radius: no partner of i lies beyond a_i + a_max + skin

  // Calls on_neighbor(j) for every partner j of i within the cutoff.
  template <class F>
  KOKKOS_INLINE_FUNCTION void operator()(const int i, F&& on_neighbor) const {
    candidates(i, Partners<F>{on_neighbor});
  }
  // The candidates within the cutoff (a functor: nvcc takes a lambda's call operator in a
  // host-device function for a host function).
  template <class F>
  struct Partners {
    F& on_neighbor;
    KOKKOS_INLINE_FUNCTION void operator()(int j, bool in) const {
      if (in) on_neighbor(j);
    }
  };
  // Calls on_candidate(j, in) for every particle j != i of i's stencil, in the same order,
  // `in` telling whether j is within the cutoff: a host sweep can then keep its partners
  // without a branch per candidate.
  template <class F>
  KOKKOS_INLINE_FUNCTION void candidates(const int i, F&& on_candidate) const {
    runs(i, Candidates<F>{*this, i, x(i, 0), x(i, 1), x(i, 2), radius(i), on_candidate});
  }
  // The candidates of the slots [s0, s1) of the cell order (a functor for nvcc, as above).
  template <class F>
  struct Candidates {
    const CellVisitor& v;
    int i;
    double xi, yi, zi, ai;
    F& on_candidate;
    KOKKOS_INLINE_FUNCTION void operator()(int s0, int s1) const {
      for (int s = s0; s < s1; ++s) {
        const int j = v.cell_particles(s);
        if (j == i) continue;
        const double rx = v.box.min_image(xi - v.x(j, 0), 0);
        const double ry = v.box.min_image(yi - v.x(j, 1), 1);
        const double rz = v.box.min_image(zi - v.x(j, 2), 2);
        const double cut = ai + v.radius(j) + v.skin;
        on_candidate(j, rx * rx + ry * ry + rz * rz < cut * cut);
      }
    }
  };
  // Calls on_run(s0, s1) for each run of consecutive slots [s0, s1) of the cell order that
  // i's stencil sweeps, in the sweep's order (i's own slot among them). The candidates are
  // cell_particles(s) for s in the runs.
  template <class F>
  KOKKOS_INLINE_FUNCTION void runs(const int i, F&& on_run) const {
    const int c = cell_of(i);
    const int cx = c % ncx, cy = (c / ncx) % ncy, cz = c / (ncx * ncy);
    // Offsets {-1,0,1} per axis, or fewer when the axis has < 3 cells, so that no cell is
    // visited twice.
    // A walled (non-periodic) axis does not wrap: its neighbour cells stop at the edges.
    const bool px = box.periodic[0], py = box.periodic[1], pz = box.periodic[2];
    const int lox = px ? (ncx >= 3 ? -1 : 0) : (cx > 0 ? -1 : 0);
    const int hix = px ? (ncx >= 2 ? 1 : 0) : (cx < ncx - 1 ? 1 : 0);
    const int loy = py ? (ncy >= 3 ? -1 : 0) : (cy > 0 ? -1 : 0);
    const int hiy = py ? (ncy >= 2 ? 1 : 0) : (cy < ncy - 1 ? 1 : 0);
    const int loz = pz ? (ncz >= 3 ? -1 : 0) : (cz > 0 ? -1 : 0);
    const int hiz = pz ? (ncz >= 2 ? 1 : 0) : (cz < ncz - 1 ? 1 : 0);
    // Cells of the stencil beyond the largest cutoff of i are skipped: the squared distance
    // from i to a neighbour cell is the sum over axes of its distance to that cell's near
    // face (zero along an axis where the cells coincide). A small particle's cutoff is well
    // inside the stencil, whose cells are sized for the largest pair. Not where an axis has
    // fewer than 3 cells (a wrapped neighbour cell lies on both sides of i there).
    double gx[3], gy[3], gz[3];
    face_gaps(x(i, 0), cx, ncx, 0, px, gx);
    face_gaps(x(i, 1), cy, ncy, 1, py, gy);
    face_gaps(x(i, 2), cz, ncz, 2, pz, gz);
    const double reach = radius(i) + a_max + skin;
    const double reach_sq = reach * reach * (1.0 + 1e-9);  // margin for the round-off of gaps
    for (int dz = loz; dz <= hiz; ++dz) {
      const int zz = wrap_cell(cz + dz, ncz);
      for (int dy = loy; dy <= hiy; ++dy) {
        const int yy = wrap_cell(cy + dy, ncy);
        const double gzy = gz[dz + 1] + gy[dy + 1];
        if (gzy > reach_sq) continue;
        // The row's cells within reach are consecutive along x, and so in the cell order
        // (x varies fastest there) unless the row wraps: each run of them is swept as one
        // range, in the same order as cell by cell, with one loop exit instead of three
        // (short loops of ~4 particles mispredict their exits).
        const int dlo = gzy + gx[0] > reach_sq ? 0 : lox, dhi = gzy + gx[2] > reach_sq ? 0 : hix;
        int first = -1, last = -1;
        for (int dx = dlo; dx <= dhi; ++dx) {
          const int cc = cell_rank((zz * ncy + yy) * ncx + wrap_cell(cx + dx, ncx));
          if (cc == last) {
            ++last;
            continue;
          }
          if (first >= 0) on_run(cell_start(first), cell_start(last));
          first = cc, last = cc + 1;
        }
        if (first >= 0) on_run(cell_start(first), cell_start(last));
      }
    }
  }

  // Cell index c (one outside the grid at most) brought back into 0 .. nc - 1: a compare
  // where the modulo's division cost ~40 integer divisions per particle and build.
  KOKKOS_INLINE_FUNCTION static int wrap_cell(int c, int nc) {
    return c < 0 ? c + nc : (c >= nc ? c - nc : c);
  }

  // Squared distances along axis d from coordinate xd (in cell c of nc) to the cells below,
  // at, and above c.
  KOKKOS_INLINE_FUNCTION void face_gaps(double xd, int c, int nc, int d, bool periodic,
                                        double g[3]) const {
    g[0] = g[1] = g[2] = 0.0;
    if (periodic && nc < 3) return;
    const double w = box.len[d] / nc;
    const double below = xd - (box.lo[d] + c * w), above = w - below;
    g[0] = below > 0.0 ? below * below : 0.0;
    g[2] = above > 0.0 ? above * above : 0.0;
  }
};

template <class ExecSpace>
class NeighborList {
 public:
  using exec = ExecSpace;
  using mem = typename ExecSpace::memory_space;
  using int_view = Kokkos::View<int*, mem>;

  explicit NeighborList(double skin = 0.0) : skin_(skin) {}

  double skin() const { return skin_; }
  int num_entries() const { return num_entries_; }  // = 2 x number of pairs
  long builds() const { return builds_; }
  const int_view& offsets() const { return offsets_; }      // n + 1
  const int_view& neighbors() const { return neighbors_; }  // offsets(n)
  // For entry k = (i, j): the entry (j, i). Lets the pair owner (i < j) compute a contact
  // once and both particles gather it in a fixed order (the multi-contact laws' two-pass
  // kernel, whose per-contact data is per entry). Kept only while keep_mirror(true) (the
  // default for a bare list; DemSystem asks for it only with a multi-contact law).
  const int_view& mirror() const { return mirror_; }
  // Whether builds make mirror(); turning it on completes the current list's at once.
  void keep_mirror(bool on) {
    keep_mirror_ = on;
    if (!on)
      mirror_ = int_view(), mirror_valid_ = false;
    else if (!mirror_valid_ && offsets_.extent(0) > 0)
      build_mirror(static_cast<int>(owned_end_.extent(0)));
  }
  // Each particle's entries come owned first: entries offsets(i) .. owned_end(i) - 1 are the
  // partners with a higher identity (contacts i owns), the rest those with a lower one. The
  // force loops then need no identity look-ups to tell them apart.
  const int_view& owned_end() const { return owned_end_; }  // n
  // Rows of the per-pair data kept only by owners (contact history): the contacts particle
  // i owns take rows pair_begin(i) .. pair_begin(i + 1) - 1, in the order of its owned
  // entries: owned entry k has row pair_begin(i) + k - offsets(i). Half the list's rows.
  const int_view& pair_begin() const { return pair_begin_; }  // n + 1
  int num_pairs() const { return num_pairs_; }
  // The pair index of the device's contact-parallel force pass, kept only while
  // keep_pair_index(true): pair_owner()(r) is the owner of pair row r (one thread per contact
  // finds its particle and list entry from it), and pair_row()(k) is the row of entry k's
  // contact, the partner's owned entry for a contact i does not own (the gather reads both
  // halves of its list from the rows).
  const int_view& pair_owner() const { return pair_owner_; }  // num_pairs()
  const int_view& pair_row() const { return pair_row_; }      // num_entries()
  void keep_pair_index(bool on) {
    keep_pair_index_ = on;
    if (!on)
      pair_owner_ = int_view(), pair_row_ = int_view(), pair_index_valid_ = false;
    else if (!pair_index_valid_ && offsets_.extent(0) > 0)
      build_pair_index(static_cast<int>(owned_end_.extent(0)));
  }
  // Particles in cell order (slab by slab, each slab in blocks of cell rows along y swept in
  // z, y, x order; identity order inside a cell, see set_partition): a particle's partners
  // sit close to it in memory.
  const int_view& cell_order() const { return cell_particles_; }
  // Slabs for the one-pass force kernel of host backends: slab s holds the particles
  // cell_order()(slab_begin()(s)) .. cell_order()(slab_begin()(s + 1) - 1), whole layers of
  // cells along z. A slab is at least one cell (one cutoff) thick, so every pair of the list
  // joins particles of the same or adjacent slabs (cyclically on a periodic axis). The slab
  // count is a multiple of 3 (or 1), so slabs 3 apart never share a particle's neighbours.
  const int_view& slab_begin() const { return slab_begin_; }  // num_slabs() + 1
  int num_slabs() const { return num_slabs_; }
  // Position of each cell (indexed (cz * ncy + cy) * ncx + cx) in the cell order.
  const int_view& cell_rank() const { return cell_rank_; }

  // The cell order and the host force pass's partition, chosen from the box alone (so every
  // sum keeps one order for any thread count). `slabs`: how many slabs along z (0:
  // default_force_slabs(); more let more threads work in each round, at the cost of locality: a
  // slab's outer layers are read again in the rounds of its neighbours); a count the box cannot
  // hold is lowered to one it can. `block_rows`: the height along y of the blocks each slab
  // is swept in. Both change the order of the force sums, so the last bits of a trajectory.
  void set_partition(int slabs, int block_rows) {
    if (slabs < 0 || block_rows < 1)
      throw InputError(
          "neighbour list partition: slabs must be >= 0 (0: automatic) and "
          "block rows >= 1");
    slabs_wanted_ = slabs, block_rows_ = block_rows;
  }
  // The slab count used for `layers` cell layers along z: each slab at least one layer thick,
  // a multiple of 3 on a periodic axis (the first and last slabs are neighbours there, and
  // the three rounds need slabs three apart to share no particle), 1 when there are too few.
  static int slab_count(int layers, bool periodic, int wanted) {
    int slabs = wanted > 0 ? wanted : default_force_slabs();
    slabs = std::min(slabs, layers);
    if (periodic) slabs = (slabs / 3) * 3;
    return slabs < 3 ? 1 : slabs;
  }

  // Build from scratch. Records the reference positions and box for the skin criterion.
  // `in_cell_order`: the caller has just called bin() on these positions and put the
  // particles in cell_order() (DemSystem's sorting); the cells are then relabelled instead
  // of binned again (the same cells and order: particle q of the new order is q-th in them).
  void build(const Particles<ExecSpace>& p, const PeriodicBox& box, bool in_cell_order = false);
  // Only the binning step of build: fills cell_order().
  void bin(const Particles<ExecSpace>& p, const PeriodicBox& box);

  // True when the list may miss a pair: 2 * max displacement since the build, plus the
  // affine shrinkage of the cutoff sphere, exceeds the skin.
  bool needs_rebuild(double max_disp_sq, const PeriodicBox& box) const {
    double shrink = 1.0;
    for (int d = 0; d < 3; ++d) shrink = std::min(shrink, box.len[d] / built_len_[d]);
    const double lost = 2.0 * std::sqrt(max_disp_sq) + (1.0 - shrink) * (2.0 * a_max_ + skin_);
    return lost >= skin_;
  }
  // Reference positions at the last build, moved affinely with the box (strain kernel).
  const typename Particles<ExecSpace>::vec_view& reference() const { return x_ref_; }

  // The list as it stands, for an exact restart (written and read by
  // scenarios/common/restart_file.hpp): a list rebuilt at restart time would differ in its
  // entry order and in when the next rebuild falls due, and so in the last bits of every force
  // sum after it. The Views are the list's own (saved() copies nothing).
  struct Saved {
    int_view offsets, neighbors;
    int_view mirror;  // empty where the list keeps none
    int_view owned_end;
    typename Particles<ExecSpace>::vec_view x_ref;
    int_view cell_order, slab_begin;  // the slabs fix the one-pass kernel's summation order
    long num_entries = 0, builds = 0;
    double a_max = 0.0;
    double built_len[3] = {0, 0, 0};
  };
  Saved saved() const {
    Saved s;
    s.offsets = offsets_, s.neighbors = neighbors_;
    if (mirror_valid_) s.mirror = mirror_;
    s.owned_end = owned_end_, s.x_ref = x_ref_;
    s.cell_order = cell_particles_, s.slab_begin = slab_begin_;
    s.num_entries = num_entries_, s.builds = builds_, s.a_max = a_max_;
    for (int d = 0; d < 3; ++d) s.built_len[d] = built_len_[d];
    return s;
  }
  // Takes a saved list as the current one, after checking every index it holds (`origin`
  // names where it came from in the errors).
  void restore(const Saved& s, const std::string& origin) {
    offsets_ = s.offsets, neighbors_ = s.neighbors;
    mirror_valid_ = s.mirror.extent(0) > 0;
    mirror_ = mirror_valid_ ? s.mirror : int_view();
    owned_end_ = s.owned_end, x_ref_ = s.x_ref;
    cell_particles_ = s.cell_order, slab_begin_ = s.slab_begin;
    num_slabs_ = static_cast<int>(slab_begin_.extent(0)) - 1;
    num_entries_ = static_cast<int>(std::min<long>(s.num_entries, 2000000000L));
    builds_ = s.builds, a_max_ = s.a_max;
    for (int d = 0; d < 3; ++d) built_len_[d] = s.built_len[d];
    check_loaded(origin);
    index_pairs(static_cast<int>(owned_end_.extent(0)));  // follows from the rows
    keep_mirror(keep_mirror_);
    pair_index_valid_ = false;
    keep_pair_index(keep_pair_index_);
  }

  // Every index a restored list holds points inside the arrays it indexes (a damaged
  // checkpoint is refused here, naming its origin, instead of read out of bounds later).
  void check_loaded(const std::string& origin) const {
    auto bad = [&](const std::string& what) {
      throw InputError(origin + ": " + what +
                       " (a damaged checkpoint: resume from an intact copy, or run again)");
    };
    const auto off = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), offsets_);
    const auto nb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), neighbors_);
    const auto own = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), owned_end_);
    const auto cells = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), cell_particles_);
    const auto slabs = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), slab_begin_);
    const long n = static_cast<long>(own.extent(0));
    if (static_cast<long>(off.extent(0)) != n + 1 || static_cast<long>(x_ref_.extent(0)) != n)
      bad("offsets, owned_end and x_ref disagree on the number of particles");
    if (off(0) != 0) bad("offsets do not start at 0");
    for (long i = 0; i < n; ++i)
      if (off(i + 1) < off(i) || own(i) < off(i) || own(i) > off(i + 1))
        bad("row " + std::to_string(i) + " has offsets or owned_end out of order");
    const long total = off(n);
    if (total > static_cast<long>(nb.extent(0)) || num_entries_ != total)
      bad("the rows hold more entries than the neighbour array");
    for (long k = 0; k < total; ++k)
      if (nb(k) < 0 || nb(k) >= n)
        bad("neighbour entry " + std::to_string(k) + " names particle " + std::to_string(nb(k)) +
            " of " + std::to_string(n));
    if (mirror_valid_) {
      const auto mir = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mirror_);
      if (static_cast<long>(mir.extent(0)) < total) bad("the mirror array is short");
      for (long k = 0; k < total; ++k)
        if (mir(k) < 0 || mir(k) >= total)
          bad("mirror entry " + std::to_string(k) + " out of range");
    }
    std::vector<char> seen(static_cast<size_t>(n), 0);
    if (static_cast<long>(cells.extent(0)) != n) bad("cell_order does not list every particle");
    for (long c = 0; c < n; ++c) {
      if (cells(c) < 0 || cells(c) >= n || seen[cells(c)])
        bad("cell_order entry " + std::to_string(c) + " is not a particle listed once");
      seen[cells(c)] = 1;
    }
    if (slabs.extent(0) < 2 || slabs(0) != 0) bad("slab_begin does not start at 0");
    for (size_t q = 1; q < slabs.extent(0); ++q)
      if (slabs(q) < slabs(q - 1) || slabs(q) > n) bad("slab_begin out of order");
    if (!(a_max_ > 0) || !(built_len_[0] > 0 && built_len_[1] > 0 && built_len_[2] > 0))
      bad("the list's radius or box is not positive");
  }

  // Public only because nvcc rejects extended lambdas in private member functions.
  void index_pairs(int n);
  // The stages of bin(): the largest radius, the cell grid (nc cells of cell_len along each
  // axis) and its arrays, the cells' order, the particles binned and sorted by identity in
  // each cell, and the slabs' first entries.
  double max_radius(const Particles<ExecSpace>& p) const;
  void cell_grid(const PeriodicBox& box, double rc, int nc[3], double cell_len[3]) const;
  void size_cells(const int nc[3], bool periodic_z, int n);
  void rank_cells(const int nc[3]);
  void fill_cells(const Particles<ExecSpace>& p, const PeriodicBox& box, const int nc[3],
                  const double cell_len[3]);
  void sort_cells(const Particles<ExecSpace>& p, int ncells);
  void mark_slabs(const int nc[3]);
  void relabel_cells(int n);
  void build_mirror(int n);
  void build_pair_index(int n);

 private:
  double skin_;
  int num_entries_ = 0;
  long builds_ = 0;
  double a_max_ = 0.0;
  double built_len_[3] = {1, 1, 1};
  int_view offsets_, neighbors_, mirror_, owned_end_, pair_begin_, pair_owner_, pair_row_;
  int num_pairs_ = 0;
  bool keep_mirror_ = true, mirror_valid_ = false;
  bool keep_pair_index_ = false, pair_index_valid_ = false;
  int_view cell_of_, cell_start_, cell_count_, cell_particles_, cell_rank_;
  int_view slab_begin_;
  int num_slabs_ = 0;
  int slabs_wanted_ = 0, block_rows_ = 4;
  static constexpr int kMaxScratch = 64;
  int scratch_cap_ = 24;  // the first build's guess; later ones follow the mean row
  int nc_[3] = {1, 1, 1};
  typename Particles<ExecSpace>::vec_view x_ref_;
};

template <class ExecSpace>
void NeighborList<ExecSpace>::bin(const Particles<ExecSpace>& p, const PeriodicBox& box) {
  a_max_ = max_radius(p);
  const double rc = 2.0 * a_max_ + skin_;
  int nc[3];
  double cell_len[3];
  cell_grid(box, rc, nc, cell_len);
  size_cells(nc, box.periodic[2], p.n);
  rank_cells(nc);
  fill_cells(p, box, nc, cell_len);
  sort_cells(p, nc[0] * nc[1] * nc[2]);
  for (int d = 0; d < 3; ++d) nc_[d] = nc[d];
  mark_slabs(nc);
}

template <class ExecSpace>
double NeighborList<ExecSpace>::max_radius(const Particles<ExecSpace>& p) const {
  auto radius = p.radius;
  double a_max = 0.0;
  Kokkos::parallel_reduce(
      "neighbor::NeighborList::max_radius", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i, double& m) { m = radius(i) > m ? radius(i) : m; },
      Kokkos::Max<double>(a_max));
  return a_max;
}

// Cells no smaller than the cutoff. The minimum image is unique only when the box is at least
// twice the cutoff.
template <class ExecSpace>
void NeighborList<ExecSpace>::cell_grid(const PeriodicBox& box, double rc, int nc[3],
                                        double cell_len[3]) const {
  for (int d = 0; d < 3; ++d) {
    // A collapsed or diverged box is not a size problem: "more particles" would be the wrong
    // advice, and a non-finite edge would reach the cell count as NaN cast to an integer.
    if (!(box.len[d] > 0) || !std::isfinite(box.len[d]))
      throw PhysicsError("box edge " + std::to_string(box.len[d]) + " along " +
                         std::string(1, static_cast<char>('x' + d)) +
                         " is not a positive length: the box collapsed or diverged (a strain " +
                         "rate too large for the run, or a non-finite state); lower the strain " +
                         "rate or the time step");
    if (!box.periodic[d]) {  // no images: any length works, cells no smaller than rc
      nc[d] = std::max(1, static_cast<int>(std::floor(box.len[d] / rc)));
      cell_len[d] = box.len[d] / nc[d];
      continue;
    }
    if (box.len[d] < 2.0 * rc)
      throw PhysicsError("box edge " + std::to_string(box.len[d]) +
                         " is shorter than twice the neighbour cutoff " + std::to_string(rc) +
                         " (largest diameter + skin): use more particles or a smaller skin");
    nc[d] = std::max(1, static_cast<int>(std::floor(box.len[d] / rc)));
    cell_len[d] = box.len[d] / nc[d];
  }
}

// The cell arrays for this grid and n particles, and the slabs of whole cell layers along z
// (see slab_begin()). On a periodic axis the first and last slabs are neighbours, so the count
// must be a multiple of 3 for the three rounds.
template <class ExecSpace>
void NeighborList<ExecSpace>::size_cells(const int nc[3], bool periodic_z, int n) {
  const int ncells = nc[0] * nc[1] * nc[2];
  if (static_cast<int>(cell_count_.extent(0)) != ncells) {
    cell_count_ = int_view("neighbor::cell_count", ncells);
    cell_start_ = int_view("neighbor::cell_start", ncells + 1);
    cell_rank_ = int_view("neighbor::cell_rank", ncells);
  }
  if (static_cast<int>(cell_of_.extent(0)) != n) {
    cell_of_ = int_view("neighbor::cell_of", n);
    cell_particles_ = int_view("neighbor::cell_particles", n);
    offsets_ = int_view("neighbor::offsets", n + 1);
    owned_end_ = int_view("neighbor::owned_end", n);
    x_ref_ = typename Particles<ExecSpace>::vec_view("neighbor::x_ref", n);
  }
  const int slabs = slab_count(nc[2], periodic_z, slabs_wanted_);
  if (static_cast<int>(slab_begin_.extent(0)) != slabs + 1)
    slab_begin_ = int_view("neighbor::slab_begin", slabs + 1);
  num_slabs_ = slabs;
}

// Cell order: slab by slab; inside a slab, blocks of `by` cell rows along y, each block swept
// in z, y, x order. A partner then lies a few blocks' worth of cells away in memory, not a
// whole layer: the sweep's working set fits the core's own cache.
template <class ExecSpace>
void NeighborList<ExecSpace>::rank_cells(const int nc[3]) {
  auto cell_rank = cell_rank_;
  const int ncx = nc[0], ncy = nc[1], layers = nc[2], slabs = num_slabs_, by = block_rows_;
  Kokkos::parallel_for(
      "neighbor::NeighborList::cell_rank", Kokkos::RangePolicy<ExecSpace>(0, ncx * ncy * layers),
      KOKKOS_LAMBDA(const int c) {
        const int cx = c % ncx, cy = (c / ncx) % ncy, cz = c / (ncx * ncy);
        // Slab s holds layers s * layers / slabs .. (s + 1) * layers / slabs - 1.
        const int s = ((cz + 1) * slabs + layers - 1) / layers - 1;
        const int z0 = static_cast<int>(static_cast<long>(s) * layers / slabs);
        const int z1 = static_cast<int>(static_cast<long>(s + 1) * layers / slabs);
        const int y0 = (cy / by) * by;
        const int h = ncy - y0 < by ? ncy - y0 : by;
        cell_rank(c) = (z0 * ncy + y0 * (z1 - z0) + (cz - z0) * h + (cy - y0)) * ncx + cx;
      });
}

// Each particle's cell, the cells' counts and starts, and the particles cell by cell (in an
// order that depends on thread timing until sort_cells).
template <class ExecSpace>
void NeighborList<ExecSpace>::fill_cells(const Particles<ExecSpace>& p, const PeriodicBox& box,
                                         const int nc[3], const double cell_len[3]) {
  auto x = p.x;
  auto cell_of = cell_of_, cell_start = cell_start_, cell_count = cell_count_;
  auto cell_particles = cell_particles_, cell_rank = cell_rank_;
  const PeriodicBox b = box;
  const int ncx = nc[0], ncy = nc[1], ncz = nc[2], ncells = ncx * ncy * ncz;
  const double clx = cell_len[0], cly = cell_len[1], clz = cell_len[2];
  Kokkos::deep_copy(cell_count, 0);
  Kokkos::parallel_for(
      "neighbor::NeighborList::bin", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i) {
        int cx = static_cast<int>((x(i, 0) - b.lo[0]) / clx);
        int cy = static_cast<int>((x(i, 1) - b.lo[1]) / cly);
        int cz = static_cast<int>((x(i, 2) - b.lo[2]) / clz);
        cx = cx < 0 ? 0 : (cx >= ncx ? ncx - 1 : cx);  // guards round-off at the faces
        cy = cy < 0 ? 0 : (cy >= ncy ? ncy - 1 : cy);
        cz = cz < 0 ? 0 : (cz >= ncz ? ncz - 1 : cz);
        const int c = (cz * ncy + cy) * ncx + cx;
        cell_of(i) = c;
        Kokkos::atomic_increment(&cell_count(cell_rank(c)));
      });
  Kokkos::parallel_scan(
      "neighbor::NeighborList::cell_scan", Kokkos::RangePolicy<ExecSpace>(0, ncells + 1),
      KOKKOS_LAMBDA(const int c, int& acc, const bool final) {
        if (final) cell_start(c) = acc;
        if (c < ncells) acc += cell_count(c);
      });
  Kokkos::deep_copy(cell_count, 0);
  Kokkos::parallel_for(
      "neighbor::NeighborList::fill_cells", Kokkos::RangePolicy<ExecSpace>(0, p.n),
      KOKKOS_LAMBDA(const int i) {
        const int c = cell_rank(cell_of(i));
        const int slot = Kokkos::atomic_fetch_add(&cell_count(c), 1);
        cell_particles(cell_start(c) + slot) = i;
      });
}

// The atomic fill order depends on thread timing; sorting each cell by particle identity
// restores a fixed order that depends only on positions and identities (not on the order
// particles happen to have in memory, so a restart reproduces it).
template <class ExecSpace>
void NeighborList<ExecSpace>::sort_cells(const Particles<ExecSpace>& p, int ncells) {
  auto id = p.id;
  auto cell_start = cell_start_, cell_particles = cell_particles_;
  Kokkos::parallel_for(
      "neighbor::NeighborList::sort_cells", Kokkos::RangePolicy<ExecSpace>(0, ncells),
      KOKKOS_LAMBDA(const int c) {
        const int s = cell_start(c), e = cell_start(c + 1);
        for (int a = s + 1; a < e; ++a) {
          const int v = cell_particles(a);
          const int idv = id(v);
          int k = a - 1;
          while (k >= s && id(cell_particles(k)) > idv) {
            cell_particles(k + 1) = cell_particles(k);
            --k;
          }
          cell_particles(k + 1) = v;
        }
      });
}

// Where each slab's particles begin in the cell order.
template <class ExecSpace>
void NeighborList<ExecSpace>::mark_slabs(const int nc[3]) {
  auto slab_begin = slab_begin_, cell_start = cell_start_;
  const int cells_per_layer = nc[0] * nc[1], layers = nc[2], slabs = num_slabs_;
  Kokkos::parallel_for(
      "neighbor::NeighborList::slabs", Kokkos::RangePolicy<ExecSpace>(0, slabs + 1),
      KOKKOS_LAMBDA(const int s) {
        const int layer = static_cast<int>(static_cast<long>(s) * layers / slabs);
        slab_begin(s) = cell_start(layer * cells_per_layer);
      });
}

template <class ExecSpace>
void NeighborList<ExecSpace>::relabel_cells(int n) {
  if (static_cast<int>(cell_of_.extent(0)) != n)
    throw std::logic_error("NeighborList::build(in_cell_order) without a bin() before it");
  auto cell_of = cell_of_, cell_start = cell_start_, cell_particles = cell_particles_;
  auto cell_rank = cell_rank_;
  const int ncells = static_cast<int>(cell_start.extent(0)) - 1;
  Kokkos::parallel_for(
      "neighbor::NeighborList::relabel", Kokkos::RangePolicy<ExecSpace>(0, ncells),
      KOKKOS_LAMBDA(const int c) {
        const int r = cell_rank(c);
        for (int q = cell_start(r); q < cell_start(r + 1); ++q)
          cell_of(q) = c, cell_particles(q) = q;
      });
}

template <class ExecSpace>
void NeighborList<ExecSpace>::build(const Particles<ExecSpace>& p, const PeriodicBox& box,
                                    bool in_cell_order) {
  if (in_cell_order)
    relabel_cells(p.n);
  else
    bin(p, box);
  const int n = p.n;
  auto x = p.x;
  auto radius = p.radius;
  const PeriodicBox b = box;
  auto cell_of = cell_of_, cell_start = cell_start_, cell_particles = cell_particles_;
  const CellVisitor<ExecSpace> visit{x, radius, cell_of, cell_start, cell_particles, cell_rank_,
                                     b, skin_,  nc_[0],  nc_[1],     nc_[2],         a_max_};

  // One stencil sweep counts each particle's partners (and the owned ones, of higher
  // identity) and keeps the first `cap` of them in a scratch row; a scan gives the offsets,
  // and the rows are copied owned first. Only the particles with more than `cap` partners
  // sweep their stencil a second time. `cap` follows the mean count (below).
  auto offsets = offsets_;
  auto owned_end = owned_end_;
  auto id = p.id;
  // The scratch lives only through the build: kept, it would add n x cap to the peak
  // memory when the contact history is remapped (old and new rows side by side) right after.
  // On host backends a row has one slot more, where the candidates not kept go: then every
  // candidate is stored and the counts advance by the test's outcome, without a branch (in a
  // stencil of ~100 candidates and ~8 partners that branch was mispredicted at nearly every
  // partner). A device keeps its branch: a store per candidate would cost it memory traffic.
  constexpr bool branch_free = std::is_same<mem, Kokkos::HostSpace>::value;
  const int cap = scratch_cap_;
  // Host rows have four slots more: the AVX sweep stores four entries at a time.
  const size_t stride = cap + (branch_free ? 4 : 0);
  int_view scratch(Kokkos::view_alloc("neighbor::scratch", Kokkos::WithoutInitializing),
                   static_cast<size_t>(n) * stride);
#if GRANULAR_HOST_AVX
  // Particles in cell order (slot s holds particle s): the candidates of a run of cells are
  // consecutive, and the sweep tests four at a time (kernels/cpu/neighbor_sweep.hpp).
  if (branch_free && in_cell_order && cpu_has_avx()) {
    const ContiguousSweep sweep{x.data(), radius.data(), id.data(), n, b, skin_};
    int* const rows = scratch.data();
    Kokkos::parallel_for("neighbor::NeighborList::count_avx", Kokkos::RangePolicy<ExecSpace>(0, n),
                         [=](const int i) {
                           const ContiguousSweep::Tally t =
                               sweep(visit, i, rows + static_cast<size_t>(i) * stride, cap);
                           offsets(i) = t.count;
                           owned_end(i) = t.owned;
                         });
  } else
#endif
    Kokkos::parallel_for(
        "neighbor::NeighborList::count", Kokkos::RangePolicy<ExecSpace>(0, n),
        KOKKOS_LAMBDA(const int i) {
          const int id_i = id(i);
          int count = 0, owned = 0;
          const size_t row = static_cast<size_t>(i) * stride;
          if (branch_free) {
            visit.candidates(i, [&](int j, bool in) {
              scratch(row + (count < cap ? count : cap)) = j;
              owned += in & (id(j) > id_i);
              count += in;
            });
          } else {
            visit(i, [&](int j) {
              if (count < cap) scratch(row + count) = j;
              ++count;
              owned += id(j) > id_i ? 1 : 0;
            });
          }
          offsets(i) = count;
          owned_end(i) = owned;
        });
  int total = 0;
  Kokkos::parallel_scan(
      "neighbor::NeighborList::scan", Kokkos::RangePolicy<ExecSpace>(0, n + 1),
      KOKKOS_LAMBDA(const int i, int& acc, const bool final) {
        const int c = i < n ? offsets(i) : 0;
        if (final) offsets(i) = acc;
        acc += c;
      },
      total);
  num_entries_ = total;
  if (static_cast<int>(neighbors_.extent(0)) < total)
    neighbors_ = int_view("neighbor::neighbors", total + total / 8 + 16);
  auto neighbors = neighbors_;
  // Rows that fit the scratch are copied from it; a row with more partners than `cap` (a
  // large particle among small ones) sweeps its stencil again, in the same order: the list is
  // the same either way.
  Kokkos::parallel_for(
      "neighbor::NeighborList::fill", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int i) {
        const int id_i = id(i);
        int ko = offsets(i), kp = offsets(i) + owned_end(i);
        owned_end(i) = kp;
        const int count = offsets(i + 1) - offsets(i);
        if (count <= cap) {
          const size_t row = static_cast<size_t>(i) * stride;
          for (int c = 0; c < count; ++c) {
            const int j = scratch(row + c);
            if (id(j) > id_i)
              neighbors(ko++) = j;
            else
              neighbors(kp++) = j;
          }
        } else {
          visit(i, [&](int j) {
            if (id(j) > id_i)
              neighbors(ko++) = j;
            else
              neighbors(kp++) = j;
          });
        }
      });
  // The scratch follows the mean row, with room for the spread of a packing's counts, not
  // the largest: n x (largest count) would be the peak of memory at every rebuild of a
  // polydisperse packing, for the sake of its few large particles.
  const int mean = n > 0 ? (total + n - 1) / n : 0;
  scratch_cap_ = std::min(kMaxScratch, std::max(8, mean + mean / 2 + 2));
  mirror_valid_ = false;
  if (keep_mirror_) build_mirror(n);
  index_pairs(n);
  pair_index_valid_ = false;
  if (keep_pair_index_) build_pair_index(n);
  Kokkos::deep_copy(x_ref_, x);
  for (int d = 0; d < 3; ++d) built_len_[d] = box.len[d];
  ++builds_;
}

template <class ExecSpace>
void NeighborList<ExecSpace>::build_mirror(int n) {
  if (mirror_.extent(0) < neighbors_.extent(0))
    mirror_ = int_view("neighbor::mirror", neighbors_.extent(0));
  auto offsets = offsets_, owned_end = owned_end_, neighbors = neighbors_, mirror = mirror_;
  Kokkos::parallel_for(
      "neighbor::NeighborList::mirror", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int i) {
        for (int k = offsets(i); k < offsets(i + 1); ++k) {
          const int j = neighbors(k);
          int m = -1;
          // i sits in the half of j's entries opposite to the half j sits in of i's.
          const bool owned = k < owned_end(i);
          const int q0 = owned ? owned_end(j) : offsets(j);
          const int q1 = owned ? offsets(j + 1) : owned_end(j);
          for (int q = q0; q < q1; ++q)
            if (neighbors(q) == i) {
              m = q;
              break;
            }
          mirror(k) = m;  // the list is symmetric by construction, so m is always found
        }
      });
  mirror_valid_ = true;
}

template <class ExecSpace>
void NeighborList<ExecSpace>::index_pairs(int n) {
  if (static_cast<int>(pair_begin_.extent(0)) != n + 1)
    pair_begin_ = int_view("neighbor::pair_begin", n + 1);
  auto offsets = offsets_, owned_end = owned_end_, pair_begin = pair_begin_;
  int total = 0;
  Kokkos::parallel_scan(
      "neighbor::NeighborList::pair_scan", Kokkos::RangePolicy<ExecSpace>(0, n + 1),
      KOKKOS_LAMBDA(const int i, int& acc, const bool final) {
        if (final) pair_begin(i) = acc;
        if (i < n) acc += owned_end(i) - offsets(i);
      },
      total);
  num_pairs_ = total;
}

template <class ExecSpace>
void NeighborList<ExecSpace>::build_pair_index(int n) {
  // Room for growth as the list's own arrays have, so that most rebuilds reallocate nothing.
  if (pair_owner_.extent(0) < static_cast<size_t>(num_pairs_) || pair_owner_.extent(0) == 0)
    pair_owner_ = int_view("neighbor::pair_owner", num_pairs_ + num_pairs_ / 8 + 8);
  if (pair_row_.extent(0) < neighbors_.extent(0))
    pair_row_ = int_view("neighbor::pair_row", neighbors_.extent(0));
  auto offsets = offsets_, owned_end = owned_end_, neighbors = neighbors_;
  auto pair_begin = pair_begin_, pair_owner = pair_owner_, pair_row = pair_row_;
  Kokkos::parallel_for(
      "neighbor::NeighborList::pair_index", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const int i) {
        const int own = owned_end(i), row0 = pair_begin(i) - offsets(i);
        for (int k = offsets(i); k < own; ++k) pair_owner(row0 + k) = i, pair_row(k) = row0 + k;
        for (int k = own; k < offsets(i + 1); ++k) {
          const int j = neighbors(k);  // the owner: i is among j's owned entries
          int r = -1;
          for (int q = offsets(j); q < owned_end(j); ++q)
            if (neighbors(q) == i) {
              r = pair_begin(j) + q - offsets(j);
              break;
            }
          pair_row(k) = r;  // the list is symmetric by construction, so r is always found
        }
      });
  pair_index_valid_ = true;
}

}  // namespace granular
