// LAMMPS dump files (`dump custom` layout): each frame an `ITEM: TIMESTEP`, `ITEM: NUMBER OF
// ATOMS`, `ITEM: BOX BOUNDS` and `ITEM: ATOMS <columns>` block, so that LAMMPS' own
// `read_dump`, `rerun`, OVITO and MDAnalysis read what the engine writes. A triclinic box is
// written as LAMMPS writes it: the bounding box of the cell followed by its tilt factors.
#pragma once
#include <string>
#include <vector>

namespace granular {

struct LammpsDumpFrame {
  long step = 0;
  double lo[3] = {0, 0, 0}, len[3] = {1, 1, 1};
  double tilt[3] = {0, 0, 0};  // xy, xz, yz
  bool triclinic = false;
  bool periodic[3] = {true, true, true};  // pp, or ff for a closed axis
  std::vector<std::string> columns;       // e.g. id type radius x y z vx vy vz
  std::vector<double> values;             // one row of columns.size() values per atom
  int atoms() const {
    return columns.empty() ? 0 : static_cast<int>(values.size() / columns.size());
  }
};

// The frame's text; the columns `id`, `type`, `mol` and `proc` are written as integers, the
// others with 17 significant digits (they read back to the same double).
std::string lammps_dump_text(const LammpsDumpFrame& frame);

}  // namespace granular
