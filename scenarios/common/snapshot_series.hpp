// Snapshots every k steps as one time series ParaView plays: <dir>/<name>.h5 holds a group
// /step_<step> per frame (position, velocity, angular_velocity, force, radius, species, id,
// box_lo and box_len, and walls/quads where the scene has walls) and <dir>/<name>.xdmf is a
// temporal collection of those frames with their simulated times. LAMMPS users know this as
// `dump every k`. The same frames go to <dir>/<name>.h5md in the H5MD layout (docs/data_formats.md)
// that MDAnalysis and other H5MD readers open: /particles/all/{position, velocity, force,
// box/edges} as value/step/time series with units, and species, id and radius.
//
// Whole or absent: the HDF5 file is written under a temporary name and renamed by finish(),
// and the XDMF file is written only after it, so an interrupted run leaves no series that
// looks finished (and an earlier complete series in the folder stays as it was).
#pragma once
#include <Kokkos_Core.hpp>
#include <memory>
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"
#include "scenarios/common/contact_network.hpp"
#include "scenarios/common/identity_order.hpp"
#include "scenarios/common/wall_config.hpp"

namespace granular {

// One frame on the host, rows in identity order (particle k is row k in every frame, so
// ParaView's point ids follow the particles whatever order the engine keeps them in).
struct SnapshotFrame {
  long step = 0;
  double time = 0;
  int n = 0, nwalls = 0;
  double box_lo[3] = {0, 0, 0}, box_len[3] = {1, 1, 1};
  bool periodic[3] = {true, true, true};
  std::vector<double> position, velocity, angular_velocity, force, radius, quads;
  std::vector<int> species, id;
  bool with_contacts = false;
  ContactNetwork contacts;  // where the series records the network
};

// `[output] snapshot_contacts = true`: each frame also holds its contact network (pairs,
// branch vectors, normal and tangential forces, overlaps). Read only where the file sets it,
// so the summaries of scenes without it do not change.
bool snapshot_contacts(const SceneFile& scene);

class SnapshotSeries {
 public:
  // every = 0: off (nothing is written).
  SnapshotSeries(std::string dir, std::string name, long every);
  SnapshotSeries(const SnapshotSeries&) = delete;
  SnapshotSeries& operator=(const SnapshotSeries&) = delete;
  ~SnapshotSeries();

  bool enabled() const { return every_ > 0; }
  // Each frame also records the contact network (off by default).
  void record_contacts(bool on) { contacts_ = on; }
  long every() const { return every_; }
  int frames() const { return static_cast<int>(steps_.size()); }
  // The next step at which a frame is due (for drivers that step in chunks).
  long next_due(long step) const { return (step / every_ + 1) * every_; }

  // Records the system's state if a frame is due: the first call, and then whenever the
  // step count has reached a multiple of k since the last frame. Drivers that advance in
  // chunks call it after each chunk; a frame then falls on the chunk's end.
  template <class System>
  void sample(const System& sys) {
    if (!enabled()) return;
    if (!steps_.empty() && sys.steps() / every_ == steps_.back() / every_) return;
    append(frame_with_contacts(sys));
  }
  // Records the final state (unless it is already the last frame), completes the HDF5 file
  // and writes the XDMF file.
  template <class System>
  void finish(const System& sys) {
    if (!enabled()) return;
    if (steps_.empty() || steps_.back() != sys.steps()) append(frame_with_contacts(sys));
    commit();
  }

  template <class System>
  static SnapshotFrame frame_of(const System& sys) {
    const auto& p = sys.particles();
    SnapshotFrame f;
    f.step = sys.steps(), f.time = sys.time(), f.n = p.n;
    const PeriodicBox& box = sys.box();
    for (int d = 0; d < 3; ++d)
      f.box_lo[d] = box.lo[d], f.box_len[d] = box.len[d], f.periodic[d] = box.periodic[d];
    ParticleRows rows = gather_by_identity(p);
    f.position = std::move(rows.position), f.velocity = std::move(rows.velocity);
    f.angular_velocity = std::move(rows.angular_velocity), f.force = std::move(rows.force);
    f.radius = std::move(rows.radius), f.species = std::move(rows.species);
    f.id.resize(f.n);
    for (int k = 0; k < f.n; ++k) f.id[k] = k;
    const auto& walls = sys.walls();
    f.nwalls = walls.size();
    for (int k = 0; k < f.nwalls; ++k) {
      const auto q = wall_quad(walls.specs()[k].normal, walls.host()(k).p, sys.box());
      f.quads.insert(f.quads.end(), q.begin(), q.end());
    }
    return f;
  }

  template <class System>
  SnapshotFrame frame_with_contacts(const System& sys) const {
    SnapshotFrame f = frame_of(sys);
    if (contacts_) f.with_contacts = true, f.contacts = contact_network(sys);
    return f;
  }

  // Appends one frame (host data); the templates above call it.
  void append(const SnapshotFrame& f);
  void commit();

 private:
  void append_h5md(const SnapshotFrame& f);
  std::string dir_, name_;
  long every_ = 0;
  bool contacts_ = false;
  std::unique_ptr<H5Writer> h5_, h5md_;
  std::vector<long> steps_;
  std::vector<double> times_;
  std::vector<int> counts_, walls_;
};

// The XDMF text of a series: a temporal collection, one frame per step (particles as
// points; walls, when there are any, as quads in a spatial collection with them).
std::string snapshot_xdmf(const std::string& h5_name, const std::vector<long>& steps,
                          const std::vector<double>& times, const std::vector<int>& counts,
                          const std::vector<int>& walls);

// "/step_00001000": frame groups sort by step in any HDF5 browser.
std::string snapshot_group(long step);

}  // namespace granular
