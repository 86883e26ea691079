// The one XDMF writer. ParaView and other XDMF readers open the engine's particle states,
// stored in HDF5, through the text it writes: a single state, a state with its walls, or a
// time series of frames (write_state's groups, the snapshot series' frames).
#pragma once
#include <string>
#include <vector>

namespace granular {

struct XdmfField {
  std::string name;
  bool vector = false;   // n x 3, else n values
  bool integer = false;  // 4-byte integers, else doubles
};

// One frame: datasets `group`/position (n x 3) and `group`/<field> for each field, the box, and the
// walls as quadrilaterals (each the quad where its plane cuts the box) read from
// `wall_dataset` (4 nwalls corners x 3) where nwalls > 0.
struct XdmfFrame {
  std::string name;  // the frame's grid name
  std::string group;
  int n = 0;
  std::vector<XdmfField> fields;
  int nwalls = 0;
  std::string wall_dataset;
  // The periodic box of the frame (it deforms over a run): `group`/box_lo and `group`/box_len
  // (3 values each) as grid-centred attributes, which ParaView shows as the grid's field data.
  bool box = false;
  bool timed = false;  // a series' frame carries its time
  double time = 0;
};

// The XDMF text naming datasets of the HDF5 file `h5_name` (a path relative to the XDMF
// file): one frame as a grid of points (a spatial collection of points and walls where it
// has walls), or, with `series`, every frame in a temporal collection.
std::string xdmf_text(const std::string& h5_name, const std::vector<XdmfFrame>& frames,
                      bool series);
// Writes it to `path` (a temporary name renamed when complete).
void write_xdmf(const std::string& path, const std::string& h5_name,
                const std::vector<XdmfFrame>& frames, bool series);

}  // namespace granular
