// Writing DEM states: a particle snapshot group in an HDF5 file (position, velocity,
// angular velocity, radius, species, id, box) that ParaView opens through an XDMF sidecar,
// and the same group read back as a starting state. A snapshot holds no contact history
// (tangential springs): exact restarts use write_restart (restart_file.hpp) instead.
#pragma once
#include <Kokkos_Core.hpp>
#include <string>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/identity_order.hpp"
#include "scenarios/common/xdmf.hpp"

namespace granular {

template <class ExecSpace>
void write_state(H5Writer& out, const std::string& group, const Particles<ExecSpace>& p,
                 const PeriodicBox& box, double density) {
  // Rows in identity order, whatever order the engine keeps in memory for locality: row k
  // is the particle of identity k (the /id column says so explicitly for readers).
  const ParticleRows rows = gather_by_identity(p);
  const int n = rows.n;
  std::vector<int> ids(n);
  for (int k = 0; k < n; ++k) ids[k] = k;
  const hsize_t nn = static_cast<hsize_t>(n);
  // The engine's units: mm, us, ug.
  write_quantity(out, group + "/position", rows.position, "mm", {nn, 3});
  write_quantity(out, group + "/velocity", rows.velocity, "mm us-1", {nn, 3});
  write_quantity(out, group + "/angular_velocity", rows.angular_velocity, "rad us-1", {nn, 3});
  write_quantity(out, group + "/radius", rows.radius, "mm");
  write_quantity(out, group + "/species", rows.species, "1");
  write_quantity(out, group + "/id", ids, "1");
  write_quantity(out, group + "/box_lo", std::vector<double>(box.lo, box.lo + 3), "mm");
  write_quantity(out, group + "/box_len", std::vector<double>(box.len, box.len + 3), "mm");
  out.attribute(group, "density", density);
}

// The XDMF frame of a group written by write_state (n particles), named "particles".
inline XdmfFrame state_frame(const std::string& group, int n) {
  XdmfFrame f;
  f.name = "particles", f.group = group, f.n = n;
  f.fields = {{"radius", false, false},
              {"velocity", true, false},
              {"angular_velocity", true, false},
              {"species", false, true},
              {"id", false, true}};
  f.box = true;
  return f;
}

// Reads a state written by write_state back into host particles and a box.
inline HostParticles read_state(const H5Reader& in, const std::string& group, PeriodicBox& box,
                                double& density) {
  const auto pos = in.reals(group + "/position");
  const auto vel = in.reals(group + "/velocity");
  const auto rad = in.reals(group + "/radius");
  const auto lo = in.reals(group + "/box_lo"), len = in.reals(group + "/box_len");
  density = in.attribute(group, "density");
  HostParticles h;
  const int n = static_cast<int>(rad.size());
  if (pos.size() != 3 * rad.size() || vel.size() != 3 * rad.size() || lo.size() != 3 ||
      len.size() != 3)
    throw InputError("state group " + group + ": array sizes do not match " + std::to_string(n) +
                     " particles and a box");
  h.resize(n);
  for (int i = 0; i < n; ++i) {
    h.x[i] = pos[3 * i], h.y[i] = pos[3 * i + 1], h.z[i] = pos[3 * i + 2];
    h.vx[i] = vel[3 * i], h.vy[i] = vel[3 * i + 1], h.vz[i] = vel[3 * i + 2];
    h.radius[i] = rad[i];
    h.density[i] = density;
  }
  // Older snapshots have neither spins nor species: those start at rest and as species 0.
  if (in.has(group + "/angular_velocity")) {
    const auto spin = in.reals(group + "/angular_velocity");
    if (spin.size() != pos.size())
      throw InputError("state group " + group + ": angular_velocity does not match " +
                       std::to_string(n) + " particles");
    for (int i = 0; i < n; ++i)
      h.wx[i] = spin[3 * i], h.wy[i] = spin[3 * i + 1], h.wz[i] = spin[3 * i + 2];
  }
  if (in.has(group + "/species")) {
    const auto species = in.ints(group + "/species");
    if (species.size() != rad.size())
      throw InputError("state group " + group + ": species does not match " + std::to_string(n) +
                       " particles");
    for (int i = 0; i < n; ++i) h.species[i] = species[i];
  }
  for (int d = 0; d < 3; ++d) box.lo[d] = lo[d], box.len[d] = len[d];
  return h;
}

}  // namespace granular
