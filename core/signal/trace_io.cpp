#include "core/signal/trace_io.hpp"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/io/output.hpp"

namespace granular {

Trace read_trace_csv(const std::string& path, int tc, int ac) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open the trace file " + path);
  Trace tr;
  std::string line;
  int lineno = 0;
  const int need = std::max(tc, ac) + 1;
  while (std::getline(in, line)) {
    ++lineno;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::replace(line.begin(), line.end(), ';', ' ');
    std::istringstream ss(line);
    std::vector<double> v;
    std::string tok;
    while (ss >> tok) {
      char* end = nullptr;
      const double x = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0') break;
      v.push_back(x);
    }
    if (v.empty()) continue;  // header, comment or blank line
    if (static_cast<int>(v.size()) < need)
      throw InputError(path + ":" + std::to_string(lineno) + ": needs " + std::to_string(need) +
                       " numeric columns, has " + std::to_string(v.size()));
    tr.t.push_back(v[tc]);
    tr.a.push_back(v[ac]);
  }
  tr.validate(path);
  return tr;
}

Trace read_trace_h5(const std::string& path, const std::string& td, const std::string& ad) {
  H5Reader in(path);
  for (const std::string& d : {td, ad})
    if (!in.has(d)) throw InputError(path + " holds no dataset " + d);
  Trace tr;
  tr.t = in.reals(td);
  tr.a = in.reals(ad);
  tr.validate(path + " (" + td + ", " + ad + ")");
  return tr;
}

std::string read_dataset_unit(const std::string& file, const std::string& dataset) {
  std::string unit;
  H5E_BEGIN_TRY {
    const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f >= 0) {
      if (H5Aexists_by_name(f, dataset.c_str(), "unit", H5P_DEFAULT) > 0) {
        const hid_t a = H5Aopen_by_name(f, dataset.c_str(), "unit", H5P_DEFAULT, H5P_DEFAULT);
        const hid_t t = a >= 0 ? H5Aget_type(a) : -1;
        const hid_t sp = a >= 0 ? H5Aget_space(a) : -1;
        if (t >= 0 && sp >= 0 && H5Tget_class(t) == H5T_STRING &&
            H5Sget_simple_extent_npoints(sp) == 1) {
          if (H5Tis_variable_str(t) > 0) {
            const hid_t m = H5Tcopy(H5T_C_S1);
            H5Tset_size(m, H5T_VARIABLE);
            H5Tset_cset(m, H5Tget_cset(t));
            char* text = nullptr;
            if (H5Aread(a, m, &text) >= 0 && text) unit = text;
            if (text) H5free_memory(text);
            H5Tclose(m);
          } else {
            std::vector<char> text(H5Tget_size(t) + 1, '\0');
            if (H5Aread(a, t, text.data()) >= 0) unit = text.data();
          }
        }
        if (sp >= 0) H5Sclose(sp);
        if (t >= 0) H5Tclose(t);
        if (a >= 0) H5Aclose(a);
      }
      H5Fclose(f);
    }
  }
  H5E_END_TRY;
  const size_t end = unit.find_last_not_of(' ');  // space-padded fixed-length strings
  return end == std::string::npos ? std::string() : unit.substr(0, end + 1);
}

}  // namespace granular
