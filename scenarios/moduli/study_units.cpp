#include "scenarios/moduli/study_units.hpp"

#include <filesystem>
#include <stdexcept>

#include "core/run/ensemble.hpp"
#include "scenarios/moduli/moduli_outputs.hpp"

namespace granular {

bool StudyDeal::mine(size_t unit) const { return owner[unit] == ensemble::rank(); }

StudyDeal deal_study_units(const std::string& parts, const std::vector<std::string>& names,
                           const std::string& fingerprint, bool resume) {
  std::string flags(names.size(), '0');
  if (ensemble::root() && resume)
    for (size_t k = 0; k < names.size(); ++k) {
      ModuliOutputs part;
      if (load_moduli_part(parts, names[k], fingerprint, part)) flags[k] = '1';
    }
  flags = ensemble::broadcast(flags);
  StudyDeal d;
  int next = 0;
  for (size_t k = 0; k < names.size(); ++k) {
    d.done.push_back(flags[k] == '1');
    d.owner.push_back(d.done.back() ? -1 : next++ % ensemble::size());
  }
  return d;
}

void collect_study_files(const std::string& parts, const std::vector<std::string>& unit_names,
                         const std::vector<std::string>& extra) {
  if (ensemble::size() == 1) return;
  std::vector<std::string> files = extra;
  if (std::filesystem::is_directory(parts))
    for (const auto& e : std::filesystem::directory_iterator(parts)) {
      if (!e.is_regular_file()) continue;
      const std::string f = e.path().filename().string();
      for (const std::string& n : unit_names)
        if (f == n + ".h5" || f == n + ".index" || f.rfind(n + "_stage", 0) == 0) {
          files.push_back(e.path().string());
          break;
        }
    }
  ensemble::collect_files(files);
}

bool gather_study_units(const std::string& parts, const std::vector<std::string>& names,
                        const std::vector<std::string>& ran, const std::vector<std::string>& extra,
                        const std::string& fingerprint, bool stopped, ModuliOutputs& out) {
  collect_study_files(parts, ran, extra);
  stopped = ensemble::any(stopped);
  if (ensemble::root() && !stopped)
    for (const std::string& name : names) {
      ModuliOutputs part;
      if (!load_moduli_part(parts, name, fingerprint, part))
        throw std::runtime_error(parts + "/" + name + ": a finished unit's part is missing");
      out.append(part);
    }
  return stopped;
}

}  // namespace granular
