// Saved configurations: a complete, host-side copy of a relaxed DEM state (positions,
// velocities, angular velocities, radii, masses, densities, species, box, per-contact
// history, phi, pressure) that a later run starts from without re-preparing it.
// A state restarts the same way whether it comes from memory or from its HDF5 file
// (fresh neighbour list in identity order, history restored by partner identity, forces
// from the stored velocities), so probing either gives bitwise the same numbers.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/host_particles.hpp"
#include "core/dem/particles.hpp"
#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/identity_order.hpp"

namespace granular {

struct ConfigState {
  HostParticles particles;  // in identity order; mass = density * 4/3 pi a^3
  std::vector<double> w;    // angular velocities, 3 per particle
  std::vector<double> mass;
  PeriodicBox box;
  int history_width = 0;            // history values per contact
  std::vector<int> pair_i, pair_j;  // identities of the contacts with history, i < j
  std::vector<double> history;      // history_width values per contact
  double phi = 0, pressure = 0;
  int size() const { return particles.size(); }
};

// Copies the state of a system into a ConfigState. `density` holds the density of each
// particle by identity (the value it was created with, so masses are restored bitwise).
template <class System>
ConfigState snapshot(const System& sys, const std::vector<double>& density, double pressure) {
  const auto& p = sys.particles();
  const int n = p.n;
  auto h = Kokkos::HostSpace();
  ParticleRows g = gather_by_identity(p);
  ConfigState c;
  c.particles = host_particles(g, [&](int k) { return density.at(k); });
  c.w = std::move(g.angular_velocity);
  c.mass = std::move(g.mass);
  c.box = sys.box();
  c.phi = sys.particle_volume() / sys.box().volume();
  c.pressure = pressure;
  // Contact history lives in the owner's slot (lower identity); only non-zero rows matter
  // (a contact without history is a fresh one).
  const auto hist = Kokkos::create_mirror_view_and_copy(h, sys.history_view());
  const int H = System::model_type::history;
  c.history_width = H;
  if (H > 0) {
    const auto& nl = sys.neighbor_list();
    auto off = Kokkos::create_mirror_view_and_copy(h, nl.offsets());
    auto own = Kokkos::create_mirror_view_and_copy(h, nl.owned_end());
    auto nb = Kokkos::create_mirror_view_and_copy(h, nl.neighbors());
    auto pb = Kokkos::create_mirror_view_and_copy(h, nl.pair_begin());
    auto id = Kokkos::create_mirror_view_and_copy(h, p.id);
    std::vector<std::pair<std::pair<int, int>, int>> rows;
    for (int i = 0; i < n; ++i)
      for (int k = off(i); k < own(i); ++k) {  // the contacts i owns, in its history rows
        const int r = pb(i) + (k - off(i));
        bool any = false;
        for (int q = 0; q < H; ++q) any = any || hist(r, q) != 0.0;
        if (any) rows.push_back({{id(i), id(nb(k))}, r});
      }
    std::sort(rows.begin(), rows.end());
    for (const auto& [pair, k] : rows) {
      c.pair_i.push_back(pair.first), c.pair_j.push_back(pair.second);
      for (int q = 0; q < H; ++q) c.history.push_back(hist(k, q));
    }
  }
  return c;
}

// Writes to a System-ready particle store (angular velocities included).
template <class ExecSpace>
Particles<ExecSpace> particles_from(const ConfigState& c) {
  Particles<ExecSpace> p = Particles<ExecSpace>::from_host(c.particles);
  auto w = Kokkos::create_mirror_view(p.w);
  for (int i = 0; i < c.size(); ++i)
    for (int d = 0; d < 3; ++d) w(i, d) = c.w[3 * i + d];
  Kokkos::deep_copy(p.w, w);
  return p;
}

// Restores the saved contact history into a freshly built system and recomputes its forces.
template <class System>
void restore_history(System& sys, const ConfigState& c) {
  constexpr int H = System::model_type::history;
  if constexpr (H > 0) {
    if (c.history_width != H && !c.pair_i.empty())
      throw InputError("saved configuration has " + std::to_string(c.history_width) +
                       " history values per contact, the contact model needs " + std::to_string(H) +
                       ": use the contact law it was prepared with");
    std::map<std::pair<int, int>, int> row;
    for (size_t r = 0; r < c.pair_i.size(); ++r)
      row[{c.pair_i[r], c.pair_j[r]}] = static_cast<int>(r);
    auto hv = sys.history_view();
    auto hist = Kokkos::create_mirror_view(hv);
    const auto& nl = sys.neighbor_list();
    auto h = Kokkos::HostSpace();
    auto off = Kokkos::create_mirror_view_and_copy(h, nl.offsets());
    auto own = Kokkos::create_mirror_view_and_copy(h, nl.owned_end());
    auto nb = Kokkos::create_mirror_view_and_copy(h, nl.neighbors());
    auto pb = Kokkos::create_mirror_view_and_copy(h, nl.pair_begin());
    auto id = Kokkos::create_mirror_view_and_copy(h, sys.particles().id);
    Kokkos::deep_copy(hist, 0.0);
    size_t restored = 0;
    for (int i = 0; i < sys.particles().n; ++i)
      for (int k = off(i); k < own(i); ++k) {  // the contacts i owns, in its history rows
        const auto it = row.find({id(i), id(nb(k))});
        if (it == row.end()) continue;
        const int r = pb(i) + (k - off(i));
        for (int q = 0; q < H; ++q) hist(r, q) = c.history[static_cast<size_t>(it->second) * H + q];
        ++restored;
      }
    if (restored != c.pair_i.size())
      throw InputError("saved configuration: " + std::to_string(c.pair_i.size() - restored) +
                       " contacts with history are not neighbours in the restored packing");
    Kokkos::deep_copy(hv, hist);
  }
  sys.refresh_forces();
}

// A system restarted from a saved configuration, with the given model and parameters.
template <class System, class Model, class Params>
System restart_system(const ConfigState& c, const Model& model, const Params& params) {
  using Exec = typename System::execution_space;
  System sys(particles_from<Exec>(c), c.box, model, params);
  restore_history(sys, c);
  return sys;
}

void write_config(const std::string& path, const ConfigState& c);
ConfigState read_config(const std::string& path);

// Another tool's packing (read_packing_file: a LAMMPS data file, an H5MD frame, a state
// group) as a state to probe: identities in the file's order, velocities and spins as read,
// no contact history (every contact starts with a fresh spring). Its pressure is not known
// before it is probed (0 here).
ConfigState config_from_packing(HostParticles particles, const PeriodicBox& box);

}  // namespace granular
