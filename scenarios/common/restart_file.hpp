// Exact restarts in HDF5: the one place where a system's saved state (DemSystem::Saved, with
// its neighbour list's and contact history's) meets a file. The kernel classes hand out and
// take back their state as Views; this writes them bit for bit and reads them back into a
// Saved state without a system, from which a system is made (DemSystem's constructor from a
// Saved state, no neighbour build first) or which a system with walls restores (checking
// every index either way).
//
// Layout of a restart group g (docs/data_formats.md, checkpoints):
//   g/particles/{x,v,w,f,torque,radius,mass,inertia,species,id}
//   g/neighbor_list/{offsets,neighbors,mirror?,owned_end,x_ref,cell_order,slab_begin,scalars}
//   g/history/{values,partner_ids,offsets,owner_rows?}   (laws with history only)
//   g/walls/{history,record}
//   g/scalars = time, steps, particle volume, then per axis lo, len, periodic, strain rate
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "kernels/dem/contact_history.hpp"
#include "kernels/dem/neighbor_list.hpp"
#include "scenarios/common/identity_order.hpp"
#include "scenarios/common/view_io.hpp"

namespace granular {

inline std::string restart_origin(const std::string& g) { return "restart group " + g; }

// `s`: a NeighborList's saved() state.
template <class ListState>
void write_list(H5Writer& out, const std::string& g, const ListState& s) {
  save_view(out, g + "/offsets", s.offsets);
  save_view(out, g + "/neighbors", s.neighbors);
  if (s.mirror.extent(0) > 0) save_view(out, g + "/mirror", s.mirror);
  save_view(out, g + "/owned_end", s.owned_end);
  save_view(out, g + "/x_ref", s.x_ref);
  save_view(out, g + "/cell_order", s.cell_order);
  save_view(out, g + "/slab_begin", s.slab_begin);
  out.write(g + "/scalars",
            std::vector<double>{static_cast<double>(s.num_entries), static_cast<double>(s.builds),
                                s.a_max, s.built_len[0], s.built_len[1], s.built_len[2]});
}

template <class ExecSpace>
typename NeighborList<ExecSpace>::Saved read_list(const H5Reader& in, const std::string& g) {
  typename NeighborList<ExecSpace>::Saved s;
  load_view(in, g + "/offsets", s.offsets);
  load_view(in, g + "/neighbors", s.neighbors);
  if (in.has(g + "/mirror")) load_view(in, g + "/mirror", s.mirror);
  load_view(in, g + "/owned_end", s.owned_end);
  load_view(in, g + "/x_ref", s.x_ref);
  if (!in.has(g + "/cell_order") || !in.has(g + "/slab_begin"))
    throw InputError(restart_origin(g) +
                     " has no slab order (written by an older version): it cannot be"
                     " continued exactly; start the run again");
  load_view(in, g + "/cell_order", s.cell_order);
  load_view(in, g + "/slab_begin", s.slab_begin);
  const auto v = in.reals(g + "/scalars");
  if (v.size() != 6) throw InputError(restart_origin(g) + " has a malformed list");
  for (double x : v)
    if (!std::isfinite(x) || x < 0 || x > 1e300)
      throw InputError(restart_origin(g) + " has a malformed list (scalars)");
  s.num_entries = static_cast<long>(std::min(v[0], 2e9)), s.builds = static_cast<long>(v[1]);
  s.a_max = v[2];
  for (int d = 0; d < 3; ++d) s.built_len[d] = v[3 + d];
  return s;
}

template <class ExecSpace>
void load_list(const H5Reader& in, const std::string& g, NeighborList<ExecSpace>& nl) {
  nl.restore(read_list<ExecSpace>(in, g), restart_origin(g));
}

template <class History>
void write_history(H5Writer& out, const std::string& g, const typename History::Saved& s) {
  if constexpr (History::columns > 0) {
    save_view(out, g + "/values", s.values);
    save_view(out, g + "/partner_ids", s.partner_ids);
    save_view(out, g + "/offsets", s.offsets);
    if (s.owner_rows) out.write(g + "/owner_rows", std::vector<double>{1.0});
  }
}

template <class History>
typename History::Saved read_history(const H5Reader& in, const std::string& g) {
  typename History::Saved s;
  if constexpr (History::columns > 0) {
    load_view(in, g + "/values", s.values);
    load_view(in, g + "/partner_ids", s.partner_ids);
    load_view(in, g + "/offsets", s.offsets);
    s.owner_rows = in.has(g + "/owner_rows");
  }
  return s;
}

// `nl`: the list restored from the same restart.
template <class History, class List>
void load_history(const H5Reader& in, const std::string& g, History& h, const List& nl) {
  h.restore(read_history<History>(in, g), nl, restart_origin(g));
}

// Writing touches nothing in the system (it reads its Views), so a run that writes
// checkpoints is bitwise the run that does not.
template <class System>
void write_restart(H5Writer& out, const std::string& g, const System& sys) {
  const auto s = sys.saved();
  const std::string pg = g + "/particles/";
  // One call per field, spelt out: nvcc's front end rejects the braced list of pairs.
  save_view(out, pg + "x", s.particles.x), save_view(out, pg + "v", s.particles.v);
  save_view(out, pg + "w", s.particles.w), save_view(out, pg + "f", s.particles.f);
  save_view(out, pg + "torque", s.particles.torque);
  save_view(out, pg + "radius", s.particles.radius);
  save_view(out, pg + "mass", s.particles.mass);
  save_view(out, pg + "inertia", s.particles.inertia);
  save_view(out, pg + "species", s.particles.species);
  save_view(out, pg + "id", s.particles.id);
  write_list(out, g + "/neighbor_list", s.list);
  write_history<typename System::history_type>(out, g + "/history", s.history);
  save_view(out, g + "/walls/history", s.wall_history);
  save_view(out, g + "/walls/touch", s.walls.touch);
  save_view(out, g + "/walls/sums", s.walls.sums);
  std::vector<double> scalars = {s.time, static_cast<double>(s.steps), s.particle_volume};
  for (int d = 0; d < 3; ++d)
    scalars.insert(scalars.end(),
                   {s.box.lo[d], s.box.len[d], s.box.periodic[d] ? 1.0 : 0.0, s.rate[d]});
  out.write(g + "/scalars", scalars);
}

// The saved state alone: no system is built to read it.
template <class System>
typename System::Saved read_restart(const H5Reader& in, const std::string& g) {
  using Exec = typename System::execution_space;
  typename System::Saved s;
  // Files of earlier versions hold one row per (particle, wall) instead of the flags and the
  // block sums (kernels/dem/wall_record.hpp).
  if (in.has(g + "/walls/record") && !in.has(g + "/walls/touch"))
    throw InputError(restart_origin(g) +
                     " was written by an earlier version of the engine (walls/record): resume it "
                     "with the version that wrote it, or start the run again");
  const auto v = in.reals(g + "/scalars");
  if (v.size() != 15) throw InputError(restart_origin(g) + " has malformed scalars");
  auto& q = s.particles;
  const std::string pg = g + "/particles/";
  load_view(in, pg + "x", q.x), load_view(in, pg + "v", q.v);
  load_view(in, pg + "w", q.w), load_view(in, pg + "f", q.f);
  load_view(in, pg + "torque", q.torque), load_view(in, pg + "radius", q.radius);
  load_view(in, pg + "mass", q.mass), load_view(in, pg + "inertia", q.inertia);
  load_view(in, pg + "species", q.species);
  load_view(in, pg + "id", q.id);
  q.n = static_cast<int>(q.x.extent(0));
  s.list = read_list<Exec>(in, g + "/neighbor_list");
  s.history = read_history<typename System::history_type>(in, g + "/history");
  load_view(in, g + "/walls/history", s.wall_history);
  load_view(in, g + "/walls/touch", s.walls.touch);
  load_view(in, g + "/walls/sums", s.walls.sums);
  s.time = v[0], s.steps = static_cast<long>(v[1]), s.particle_volume = v[2];
  for (int d = 0; d < 3; ++d) {
    s.box.lo[d] = v[3 + 4 * d], s.box.len[d] = v[4 + 4 * d];
    s.box.periodic[d] = v[5 + 4 * d] != 0.0, s.rate[d] = v[6 + 4 * d];
  }
  return s;
}

// Continues `sys` (made from the same particles, model, parameters and walls) bitwise where
// the saved system was.
template <class System>
void load_restart(const H5Reader& in, const std::string& g, System& sys) {
  sys.restore(read_restart<System>(in, g), restart_origin(g));
}

}  // namespace granular
