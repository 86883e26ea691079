// Snapshot time series for ParaView (see snapshot_series.hpp).
#include "scenarios/common/snapshot_series.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "granular_config.hpp"
#include "scenarios/common/xdmf.hpp"

namespace granular {

std::string snapshot_group(long step) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "/step_%08ld", step);
  return buf;
}

bool snapshot_contacts(const SceneFile& scene) {
  return scene.has("output.snapshot_contacts") && scene.flag("output.snapshot_contacts");
}

SnapshotSeries::SnapshotSeries(std::string dir, std::string name, long every)
    : dir_(std::move(dir)), name_(std::move(name)), every_(every > 0 ? every : 0) {}

// An unfinished series (the run stopped or failed) leaves nothing: H5Writer removes its
// temporary file, and no XDMF file was written.
SnapshotSeries::~SnapshotSeries() = default;

void SnapshotSeries::append(const SnapshotFrame& f) {
  // The file is opened on the first frame, so a run that never records one writes nothing.
  if (!h5_) h5_ = std::make_unique<H5Writer>(dir_ + "/" + name_ + ".h5");
  const std::string g = snapshot_group(f.step);
  const hsize_t n = static_cast<hsize_t>(f.n);
  h5_->write(g + "/position", f.position, {n, 3});
  h5_->write(g + "/velocity", f.velocity, {n, 3});
  h5_->write(g + "/angular_velocity", f.angular_velocity, {n, 3});
  h5_->write(g + "/force", f.force, {n, 3});
  h5_->write(g + "/radius", f.radius);
  h5_->write(g + "/species", f.species);
  h5_->write(g + "/id", f.id);
  if (f.with_contacts) {
    const ContactNetwork& c = f.contacts;
    const hsize_t m = static_cast<hsize_t>(c.size());
    std::vector<int> pairs;
    for (int k = 0; k < c.size(); ++k) pairs.push_back(c.i[k]), pairs.push_back(c.j[k]);
    h5_->write(g + "/contacts/pair", pairs, {m, 2});
    h5_->write(g + "/contacts/branch", c.branch, {m, 3});
    h5_->write(g + "/contacts/normal_force", c.normal_force, {m});
    h5_->write(g + "/contacts/tangential_force", c.tangential_force, {m, 3});
    h5_->write(g + "/contacts/overlap", c.overlap, {m});
  }
  h5_->write(g + "/box_lo", std::vector<double>(f.box_lo, f.box_lo + 3));
  h5_->write(g + "/box_len", std::vector<double>(f.box_len, f.box_len + 3));
  if (f.nwalls > 0)
    h5_->write(g + "/walls/quads", f.quads, {static_cast<hsize_t>(4 * f.nwalls), 3});
  h5_->attribute(g, "time", f.time);
  h5_->attribute(g, "step", static_cast<double>(f.step));
  steps_.push_back(f.step);
  times_.push_back(f.time);
  counts_.push_back(f.n);
  walls_.push_back(f.nwalls);
  append_h5md(f);
}

void SnapshotSeries::append_h5md(const SnapshotFrame& f) {
  const std::string p = "/particles/all";
  if (!h5md_) {
    h5md_ = std::make_unique<H5Writer>(dir_ + "/" + name_ + ".h5md");
    H5Writer& h = *h5md_;
    h.attribute("/h5md", "version", std::vector<int>{1, 1});
    h.attribute_utf8("/h5md/author", "name", "granular");
    h.attribute_utf8("/h5md/creator", "name", "granular");
    h.attribute_utf8("/h5md/creator", "version", GRANULAR_VERSION);
    h.attribute("/h5md/modules/units", "version", std::vector<int>{1, 0});
    h.attribute_int(p + "/box", "dimension", 3);
    std::vector<std::string> boundary;
    for (int d = 0; d < 3; ++d) boundary.push_back(f.periodic[d] ? "periodic" : "none");
    h.attribute(p + "/box", "boundary", boundary);
    // Time-independent: the same particles in every frame, rows in identity order.
    h.write(p + "/species", f.species);
    h.write(p + "/id", f.id);
    h.write(p + "/radius", f.radius);
    h.attribute_utf8(p + "/radius", "unit", "mm");
  }
  H5Writer& h = *h5md_;
  const hsize_t n = static_cast<hsize_t>(f.n);
  struct Element {
    const char* name;
    const std::vector<double>* value;
    const char* unit;
  };
  // The edges as the box matrix (one edge vector per row; H5MD allows the diagonal alone,
  // but MDAnalysis reads the matrix).
  const std::vector<double> edges = {f.box_len[0], 0, 0, 0, f.box_len[1], 0, 0, 0, f.box_len[2]};
  const Element elements[] = {{"box/edges", &edges, "mm"},
                              {"position", &f.position, "mm"},
                              {"velocity", &f.velocity, "mm us-1"},
                              {"force", &f.force, "N"}};
  const bool first = steps_.size() == 1;
  for (const Element& e : elements) {
    const std::string g = p + "/" + e.name;
    const bool per_particle = e.value != &edges;
    h.append(g + "/value", *e.value, std::vector<hsize_t>{per_particle ? n : 3, 3});
    h.append(g + "/step", std::vector<long>{f.step});
    h.append(g + "/time", std::vector<double>{f.time});
    if (first) {
      h.attribute_utf8(g + "/value", "unit", e.unit);
      h.attribute_utf8(g + "/time", "unit", "us");
    }
  }
}

void SnapshotSeries::commit() {
  if (!h5_) return;
  // The XDMF file of an earlier version of this series (a resumed run starts its series
  // afresh where it resumed) goes before the new .h5 replaces the old one: it names frames
  // the new file does not hold, so a kill between the two commits would leave a mixed set.
  std::error_code gone;
  std::filesystem::remove(dir_ + "/" + name_ + ".xdmf", gone);
  h5_->attribute("/", "snapshot_every", static_cast<double>(every_));
  h5_->commit();
  h5_.reset();
  h5md_->commit();
  h5md_.reset();
  write_text_file(dir_ + "/" + name_ + ".xdmf",
                  snapshot_xdmf(name_ + ".h5", steps_, times_, counts_, walls_));
}

std::string snapshot_xdmf(const std::string& h5_name, const std::vector<long>& steps,
                          const std::vector<double>& times, const std::vector<int>& counts,
                          const std::vector<int>& walls) {
  std::vector<XdmfFrame> frames(steps.size());
  for (size_t k = 0; k < steps.size(); ++k) {
    XdmfFrame& f = frames[k];
    f.group = snapshot_group(steps[k]);
    f.name = f.group.substr(1);
    f.n = counts[k];
    f.fields = {{"radius", false, false},          {"velocity", true, false},
                {"angular_velocity", true, false}, {"force", true, false},
                {"species", false, true},          {"id", false, true}};
    f.nwalls = walls[k];
    f.wall_dataset = f.group + "/walls/quads";
    f.box = true;
    f.timed = true, f.time = times[k];
  }
  return xdmf_text(h5_name, frames, true);
}

}  // namespace granular
