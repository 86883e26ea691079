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
  try {
    return H5Reader(file).text_attribute(dataset, "unit");
  } catch (const InputError&) {  // no such file, or not HDF5: no unit
    return std::string();
  }
}

}  // namespace granular
