// The host one-pass force kernel's raw views of particles and list rows, and the near
// list's rows (kernels/dem/contact_forces.hpp, kernels/cpu/near_stream.hpp).
#pragma once
#include <Kokkos_Core.hpp>

#include "core/dem/particles.hpp"
#include "kernels/dem/neighbor_list.hpp"

namespace granular {

// Raw-pointer views of the particle fields for the host kernel: the same accessors as
// ParticleViews, without the View's run-time strides and the reloads of its metadata that
// the compiler cannot rule out around the scattered stores.
struct HostVec3 {
  double* p;
  KOKKOS_FORCEINLINE_FUNCTION double& operator()(int i, int d) const { return p[3 * i + d]; }
};
template <class T>
struct HostArray {
  T* p;
  KOKKOS_FORCEINLINE_FUNCTION T& operator()(int i) const { return p[i]; }
};
struct HostParticleViews {
  HostVec3 x, v, w;
  HostArray<double> radius, mass;
  HostArray<int> species;
  template <class ExecSpace>
  explicit HostParticleViews(const Particles<ExecSpace>& p)
      : x{p.x.data()},
        v{p.v.data()},
        w{p.w.data()},
        radius{p.radius.data()},
        mass{p.mass.data()},
        species{p.species.data()} {}
};

// The neighbour list's rows for the host kernel (raw pointers, as HostParticleViews).
struct HostListRows {
  HostArray<const int> offsets, owned_end, neighbors, pair_begin;
  template <class ExecSpace>
  explicit HostListRows(const NeighborList<ExecSpace>& nl)
      : offsets{nl.offsets().data()},
        owned_end{nl.owned_end().data()},
        neighbors{nl.neighbors().data()},
        pair_begin{nl.pair_begin().data()} {}
};

// A contact that is apart forgets its history. Most such slots are already zero: reading is
// cheaper than rewriting them every step.
template <int H>
KOKKOS_FORCEINLINE_FUNCTION void forget_history(double* hist, int k) {
  if (H > 0) {
    bool stale = false;
    for (int c = 0; c < H; ++c) stale = stale || hist[k * H + c] != 0.0;
    if (stale)
      for (int c = 0; c < H; ++c) hist[k * H + c] = 0.0;
  }
}

struct NearStream;  // kernels/cpu/near_stream.hpp

// The near list of the host kernel: each particle's owned entries within a second, smaller
// skin of touching, in list order (a subsequence of its row). While no particle has moved
// half that skin since it was recorded, every other entry of the row is apart and stays
// apart, its history already forgotten: the force pass reads only the near entries, and the
// touching contacts, their order and so every sum are the same as from the whole row.
// Recorded by any force pass over the whole rows (ListEntries), read by the next ones
// (NearEntries); DemSystem decides which (near_skin in DemParams).
struct NearRows {
  int* k = nullptr;      // near entries (list indices), particle i's from pair_begin(i) on
  int* count = nullptr;  // near entries per particle
  double skin = 0.0;     // the near skin the rows are recorded with
  // Where the recordings also write the near list as a flat stream and the readings take it
  // from (kernels/cpu/near_stream.hpp; null: the rows are read as recorded).
  NearStream* stream = nullptr;
  // The particles' packed records (kernels/cpu/particle_pack.hpp), holding this step's positions,
  // radii, velocities and spins, where the step wrote them for the frictional stream's reads (null:
  // the stream reads the arrays).
  const double* pack = nullptr;
};

}  // namespace granular
