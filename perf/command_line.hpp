// The benchmarks' command lines: comma-separated lists, and options read in order.
#pragma once
#include <functional>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace granular::perf {

inline std::vector<std::string> word_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

inline std::vector<double> number_list(const std::string& s) {
  std::vector<double> out;
  for (const std::string& w : word_list(s)) out.push_back(std::stod(w));
  return out;
}

// Offers each option but Kokkos' own (--kokkos-*) to take(name, value), where value() reads
// the option's value (the next argument; throws when there is none). Returns false, naming the
// option on stderr, when take() does not know it.
inline bool read_options(
    int argc, char** argv,
    const std::function<bool(const std::string&, const std::function<std::string()>&)>& take) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--kokkos", 0) == 0) continue;
    const std::function<std::string()> value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("missing value after " + a);
      return argv[++i];
    };
    if (!take(a, value)) {
      std::cerr << "unknown option " << a << "\n";
      return false;
    }
  }
  return true;
}

}  // namespace granular::perf
