#include "scenarios/common/xdmf.hpp"

#include <sstream>

#include "core/io/output.hpp"

namespace granular {

std::string xdmf_text(const std::string& h5_name, const std::vector<XdmfFrame>& frames,
                      bool series) {
  std::ostringstream x;
  x.precision(17);
  auto item = [&](const std::string& dims, const char* type, int precision,
                  const std::string& path) {
    x << "<DataItem Dimensions=\"" << dims << "\" NumberType=\"" << type << "\" Precision=\""
      << precision << "\" Format=\"HDF\">" << h5_name << ":" << path << "</DataItem>";
  };
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n";
  if (series) x << "  <Grid Name=\"series\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  const std::string base = series ? "   " : "  ";
  for (const XdmfFrame& f : frames) {
    const std::string n = std::to_string(f.n);
    const bool with_walls = f.nwalls > 0;
    const std::string ind = with_walls ? base + " " : base;
    auto time = [&](const std::string& at) {
      if (f.timed) x << at << "<Time Value=\"" << f.time << "\"/>\n";
    };
    if (with_walls) {
      x << base << "<Grid Name=\"" << f.name << "\" GridType=\"Collection\" "
        << "CollectionType=\"Spatial\">\n";
      time(ind);
    }
    x << ind << "<Grid Name=\"" << (with_walls ? "particles" : f.name)
      << "\" GridType=\"Uniform\">\n";
    time(ind + " ");
    x << ind << " <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\"/>\n"
      << ind << " <Geometry GeometryType=\"XYZ\">";
    item(n + " 3", "Float", 8, f.group + "/position");
    x << "</Geometry>\n";
    for (const XdmfField& a : f.fields) {
      x << ind << " <Attribute Name=\"" << a.name << "\" AttributeType=\""
        << (a.vector ? "Vector" : "Scalar") << "\" Center=\"Node\">";
      item(a.vector ? n + " 3" : n, a.integer ? "Int" : "Float", a.integer ? 4 : 8,
           f.group + "/" + a.name);
      x << "</Attribute>\n";
    }
    if (f.box)
      for (const char* b : {"box_lo", "box_len"}) {
        x << ind << " <Attribute Name=\"" << b << "\" AttributeType=\"Vector\" Center=\"Grid\">";
        item("3", "Float", 8, f.group + "/" + b);
        x << "</Attribute>\n";
      }
    x << ind << "</Grid>\n";
    if (with_walls) {
      x << ind << "<Grid Name=\"walls\" GridType=\"Uniform\">\n";
      time(ind + " ");
      x << ind << " <Topology TopologyType=\"Quadrilateral\" NumberOfElements=\"" << f.nwalls
        << "\">"
        << "<DataItem Dimensions=\"" << f.nwalls << " 4\" NumberType=\"Int\" Format=\"XML\">";
      for (int c = 0; c < 4 * f.nwalls; ++c) x << (c ? " " : "") << c;
      x << "</DataItem></Topology>\n" << ind << " <Geometry GeometryType=\"XYZ\">";
      item(std::to_string(4 * f.nwalls) + " 3", "Float", 8, f.wall_dataset);
      x << "</Geometry>\n" << ind << "</Grid>\n" << base << "</Grid>\n";
    }
  }
  if (series) x << "  </Grid>\n";
  x << " </Domain>\n</Xdmf>\n";
  return x.str();
}

void write_xdmf(const std::string& path, const std::string& h5_name,
                const std::vector<XdmfFrame>& frames, bool series) {
  write_text_file(path, xdmf_text(h5_name, frames, series));
}

}  // namespace granular
