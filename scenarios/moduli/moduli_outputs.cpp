#include "scenarios/moduli/moduli_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "core/io/dataset_units.hpp"
#include "core/run/ensemble.hpp"
#include "core/run/error.hpp"

namespace granular {

void ModuliOutputs::add_row(const std::string& tag, const std::map<std::string, double>& row) {
  Json r = Json::object();
  r["tag"] = tag;
  for (const auto& [k, v] : row) r[k] = v, table[k].push_back(v);
  rows.push(r);
  table_tags.push_back(tag);
}

void ModuliOutputs::add_sweep(const SweepMeta& meta,
                              const std::map<std::string, std::vector<double>>& columns) {
  Json j = Json::object();
  j["tag"] = meta.tag, j["phi"] = meta.phi, j["z_corrected"] = meta.z_corrected;
  for (const auto& [k, v] : columns) {
    j[k] = Json(v);
    sweep_data.push_back({meta.group + "/" + k, v});
  }
  sweeps.push(j);
  sweep_meta.push_back(meta);
}

std::vector<SizeScatter> size_scatter(const std::map<std::string, std::vector<double>>& table) {
  std::vector<SizeScatter> out;
  for (const char* key : {"particles", "phi_target", "jammed", "K_star", "G_star"})
    if (!table.count(key)) return out;
  const auto& n = table.at("particles");
  const auto& t = table.at("phi_target");
  const auto& jammed = table.at("jammed");
  const auto& K = table.at("K_star");
  const auto& G = table.at("G_star");
  const auto mu_col = table.find("mu_preparation");
  const auto mu_of = [&](size_t i) {
    return mu_col == table.end() ? std::nan("") : mu_col->second[i];
  };
  // A NaN friction (not set per variant) cannot order a map key: it groups as -1.
  const auto mu_key = [&](size_t i) { return std::isnan(mu_of(i)) ? -1.0 : mu_of(i); };
  std::map<std::tuple<double, double, double>, std::vector<size_t>> groups;
  for (size_t i = 0; i < n.size(); ++i)
    if (jammed[i] > 0) groups[{mu_key(i), n[i], t[i]}].push_back(i);
  bool repeated = false;
  for (const auto& [key, rows] : groups) repeated = repeated || rows.size() > 1;
  if (!repeated) return out;
  for (const auto& [key, rows] : groups) {
    SizeScatter e;
    e.mu = mu_of(rows[0]);
    e.particles = std::get<1>(key), e.phi_target = std::get<2>(key);
    e.samples = static_cast<int>(rows.size());
    for (size_t i : rows) e.K_mean += K[i], e.G_mean += G[i];
    e.K_mean /= e.samples, e.G_mean /= e.samples;
    for (size_t i : rows)
      e.K_std += (K[i] - e.K_mean) * (K[i] - e.K_mean),
          e.G_std += (G[i] - e.G_mean) * (G[i] - e.G_mean);
    const double dof = e.samples > 1 ? e.samples - 1.0 : 1.0;
    e.K_std = std::sqrt(e.K_std / dof), e.G_std = std::sqrt(e.G_std / dof);
    out.push_back(e);
  }
  return out;
}

void ModuliOutputs::add_config(const std::string& path) {
  configs.push(Json(path));
  config_paths.push_back(path);
}

void ModuliOutputs::add(const ConfigResults& c) {
  if (!c.config.empty()) add_config(c.config);
  for (const TableRow& r : c.rows) add_row(r.tag, r.values);
  for (const SweepColumns& w : c.sweeps) add_sweep(w.meta, w.columns);
}

void ModuliOutputs::append(const ModuliOutputs& part) {
  // Rows and sweeps are rebuilt through add_* so the summary and the datasets stay in step.
  const size_t n = part.table_tags.size();
  for (size_t i = 0; i < n; ++i) {
    std::map<std::string, double> row;
    for (const auto& [k, v] : part.table) row[k] = v.at(i);
    // Checkpoints written before the "jammed" column marked unjammed rows by Z = 0.
    if (!part.table.count("jammed") && row.count("z_corrected"))
      row["jammed"] = row["z_corrected"] > 0 ? 1.0 : 0.0;
    add_row(part.table_tags[i], row);
  }
  for (const auto& [k, v] : part.prep) prep[k].insert(prep[k].end(), v.begin(), v.end());
  for (const SweepMeta& m : part.sweep_meta) add_sweep(m, part.sweep_columns(m.group));
  for (const std::string& p : part.config_paths) add_config(p);
}

std::map<std::string, std::vector<double>> ModuliOutputs::sweep_columns(
    const std::string& group) const {
  std::map<std::string, std::vector<double>> cols;
  const std::string prefix = group + "/";
  for (const auto& [name, v] : sweep_data)
    if (name.compare(0, prefix.size(), prefix) == 0) cols[name.substr(prefix.size())] = v;
  return cols;
}

const std::string& column_unit(const ColumnUnits& units, const std::string& column,
                               const std::string& dataset) {
  const auto it = units.find(column);
  if (it == units.end())
    throw std::logic_error("results.h5: dataset " + dataset +
                           " has no unit; add its column to the scene's unit table");
  return it->second;
}

void ModuliOutputs::write_results(H5Writer& h5, const ModuliUnits& units) const {
  // The sweep column is the last part of the dataset's path (names never hold '/').
  const auto sweep_column = [](const std::string& name) {
    return name.substr(name.rfind('/') + 1);
  };
  // All units first: a column left out of the table stops here, before any dataset is written.
  std::vector<std::string> table_units, prep_units, sweep_units;
  for (const auto& [k, v] : table)
    table_units.push_back(column_unit(units.table, k, "/table/" + k));
  for (const auto& [k, v] : prep)
    prep_units.push_back(column_unit(units.prep, k, "/preparation/" + k));
  for (const auto& [k, v] : sweep_data)
    sweep_units.push_back(column_unit(units.sweep, sweep_column(k), k));
  size_t i = 0;
  for (const auto& [k, v] : table) write_quantity(h5, "/table/" + k, v, table_units[i++]);
  i = 0;
  for (const auto& [k, v] : prep) write_quantity(h5, "/preparation/" + k, v, prep_units[i++]);
  i = 0;
  for (const auto& [k, v] : sweep_data) write_quantity(h5, k, v, sweep_units[i++]);
}

namespace {
std::string parameter_fingerprint(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}
}  // namespace

std::string study_checkpoints(const std::string& out_dir) { return out_dir + "/variants"; }

namespace {
std::string removal_name(const std::string& parts) {
  const std::filesystem::path p(parts);
  return (p.parent_path() / ("." + p.filename().string() + ".removing")).string();
}
}  // namespace

void remove_study_checkpoints(const std::string& parts) {
  if (!ensemble::root() || !std::filesystem::exists(parts)) return;
  const std::string gone = removal_name(parts);
  std::filesystem::remove_all(gone);
  std::filesystem::rename(parts, gone);
  std::filesystem::remove_all(gone);
}

std::string open_study_checkpoints(const std::string& out_dir, bool resume) {
  const std::string parts = study_checkpoints(out_dir);
  if (ensemble::root()) std::filesystem::remove_all(removal_name(parts));  // a killed removal
  // Rank 0 alone judges the folder: on a shared file system another rank may already be
  // writing its first stage checkpoint there when a slower one gets here.
  if (ensemble::root() && !resume && std::filesystem::exists(parts) &&
      !std::filesystem::is_empty(parts))
    throw InputError(parts + " holds checkpoints of an unfinished study: continue it with " +
                     "--resume, or remove that directory (or choose another --out) to start over");
  make_directories(parts);
  return parts;
}

std::string moduli_parameters_fingerprint(const std::map<std::string, std::string>& used) {
  // How far a run goes, and the overlap guard (it changes whether a run may go on, never its
  // trajectory), are not parameters of its results: resuming may change them. Keys added
  // after the layout version, at the default that reproduces the runs made before them, are
  // left out as well, so checkpoints written before such a key existed stay resumable.
  const std::map<std::string, std::string> later_keys_at_old_default = {
      {"probe.orientations", "1"}};
  std::string text = "moduli outputs v2\n";
  for (const auto& [k, v] : used) {
    const auto later = later_keys_at_old_default.find(k);
    if (later != later_keys_at_old_default.end() && later->second == v) continue;
    if (k.rfind("run.stop_after_", 0) == 0 || k == "run.max_overlap") continue;
    text += k + "=" + v + "\n";
  }
  return parameter_fingerprint(text);
}

// Index lines: "fingerprint F", then "<kind> <name>" with kind table/prep/sweep/config/tag;
// sweep lines carry "<group> <tag> <phi> <z> <column>..." (names never hold spaces).
void save_moduli_part(const std::string& dir, const std::string& name,
                      const std::string& fingerprint, const ModuliOutputs& part) {
  make_directories(dir);
  H5Writer h5(dir + "/" + name + ".h5");
  std::ostringstream index;
  index.precision(17);
  index << "fingerprint " << fingerprint << "\n";
  for (const auto& [k, v] : part.table) h5.write("/table/" + k, v), index << "table " << k << "\n";
  for (const auto& [k, v] : part.prep)
    h5.write("/preparation/" + k, v), index << "prep " << k << "\n";
  for (const auto& [k, v] : part.sweep_data) h5.write(k, v);
  for (const auto& m : part.sweep_meta) {
    index << "sweep " << m.group << " " << (m.tag.empty() ? "-" : m.tag) << " " << m.phi << " "
          << m.z_corrected;
    for (const auto& [col, v] : part.sweep_columns(m.group)) index << " " << col;
    index << "\n";
  }
  for (const auto& t : part.table_tags) index << "tag " << (t.empty() ? "-" : t) << "\n";
  // Configurations inside the study's output folder (the parent of `dir`) are stored
  // relative to it, so a moved or copied folder resumes listing its own files.
  const std::string out_dir = std::filesystem::path(dir).parent_path().string() + "/";
  for (const auto& p : part.config_paths) {
    if (p.compare(0, out_dir.size(), out_dir) == 0)
      index << "config_in_output " << p.substr(out_dir.size()) << "\n";
    else
      index << "config " << p << "\n";
  }
  // The number of entry lines closes the index: a line lost or cut off is then noticed on
  // resume instead of leaving a column out of the results.
  const std::string body = index.str();
  const long lines = std::count(body.begin(), body.end(), '\n') - 1;
  h5.commit();
  write_text_file(dir + "/" + name + ".index", body + "end " + std::to_string(lines) + "\n");
}

bool load_moduli_part(const std::string& dir, const std::string& name,
                      const std::string& fingerprint, ModuliOutputs& part) {
  const std::string index_path = dir + "/" + name + ".index";
  std::ifstream in(index_path);
  if (!in) return false;
  std::string kind, value, line;
  in >> kind >> value;
  if (kind != "fingerprint" || value != fingerprint)
    throw InputError(index_path +
                     ": this checkpoint was written by a run with other scene parameters; "
                     "continue with the scene file it was made with, or run without --resume "
                     "into an empty output directory");
  H5Reader h5(dir + "/" + name + ".h5");
  auto untag = [](const std::string& t) { return t == "-" ? std::string() : t; };
  long entries = 0, declared = -1;
  while (in >> kind) {
    std::getline(in, line);
    std::istringstream rest(line);
    if (declared >= 0)
      throw InputError(index_path +
                       ": lines after its end; the checkpoint is damaged: run "
                       "without --resume into an empty output directory");
    if (kind != "end") ++entries;
    if (kind == "end") {
      if (!(rest >> declared) || declared < 0) declared = -2;
    } else if (kind == "table") {
      rest >> value, part.table[value] = h5.reals("/table/" + value);
    } else if (kind == "prep") {
      rest >> value, part.prep[value] = h5.reals("/preparation/" + value);
    } else if (kind == "tag") {
      rest >> value, part.table_tags.push_back(untag(value));
    } else if (kind == "config") {
      rest >> value, part.add_config(value);
    } else if (kind == "config_in_output") {  // the rest of the line: spaces allowed
      value = line.substr(std::min(line.find_first_not_of(' '), line.size()));
      part.add_config(std::filesystem::path(dir).parent_path().string() + "/" + value);
    } else if (kind == "sweep") {
      ModuliOutputs::SweepMeta m;
      std::string tag;
      rest >> m.group >> tag >> m.phi >> m.z_corrected;
      m.tag = untag(tag);
      std::map<std::string, std::vector<double>> cols;
      while (rest >> value) cols[value] = h5.reals(m.group + "/" + value);
      part.add_sweep(m, cols);
    } else {
      throw InputError(index_path + ": unreadable checkpoint index line '" + kind + line + "'");
    }
  }
  if (declared != entries)
    throw InputError(index_path + ": " +
                     (declared < 0 ? std::string("no end line")
                                   : std::to_string(entries) +
                                         " entries where its end line "
                                         "counts " +
                                         std::to_string(declared)) +
                     "; the checkpoint is damaged or cut short: run without --resume into an "
                     "empty output directory");
  return true;
}

}  // namespace granular
