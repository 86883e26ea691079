// What an elastic-moduli study accumulates (table rows, preparation series, amplitude
// sweeps, saved configurations), and its per-variant checkpoints: a full study prepares
// several packings for hours, so each finished preparation variant is written to
// <out>/variants/ and a run continued with --resume takes it from there instead of
// preparing it again.
#pragma once
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/io/output.hpp"

namespace granular {

// The unit of each column of a study by its name (H5MD spelling, "1" for a pure number):
// the parts a study checkpoints and merges hold values only, so the units are attached where
// results.h5 is written, from the driver's own table of its columns.
using ColumnUnits = std::map<std::string, std::string>;
struct ModuliUnits {
  ColumnUnits table;  // /table/<column>
  ColumnUnits prep;   // /preparation/<column>
  ColumnUnits sweep;  // <group>/<column> of the sweeps, by the column's name in its group
};
// The unit of `column`; a column without one is a programming error (std::logic_error naming
// `dataset`): every dataset of results.h5 carries its unit.
const std::string& column_unit(const ColumnUnits& units, const std::string& column,
                               const std::string& dataset);

struct ConfigResults;

struct ModuliOutputs {
  Json rows = Json::array();
  Json sweeps = Json::array();
  Json configs = Json::array();
  std::map<std::string, std::vector<double>> table;
  std::map<std::string, std::vector<double>> prep;  // preparation series
  std::vector<std::pair<std::string, std::vector<double>>> sweep_data;
  // Per sweep group (e.g. "/sweep/mu0.5_phi_0.6800"): tag, phi and Z of the configuration.
  struct SweepMeta {
    std::string group, tag;
    double phi = 0, z_corrected = 0;
  };
  std::vector<SweepMeta> sweep_meta;
  std::vector<std::string> table_tags;  // tag of each table row
  std::vector<std::string> config_paths;

  // Appends one table row (the row also goes to summary.json, labelled with its tag).
  void add_row(const std::string& tag, const std::map<std::string, double>& row);
  // Appends one amplitude sweep of a configuration (columns by name) under `group`.
  void add_sweep(const SweepMeta& meta, const std::map<std::string, std::vector<double>>& columns);
  void add_config(const std::string& path);
  // What one probed configuration gave: its file (where it has one), rows and sweeps.
  void add(const ConfigResults& c);
  // Everything of `part` appended after what is already here.
  void append(const ModuliOutputs& part);
  // The sweep columns stored under `group`, by name.
  std::map<std::string, std::vector<double>> sweep_columns(const std::string& group) const;
  // Writes the table (/table/<column>), the preparation series (/preparation/<column>) and
  // the sweeps (<group>/<column>) into `h5`, each with its unit from `units`. Every column's
  // unit is looked up before anything is written.
  void write_results(H5Writer& h5, const ModuliUnits& units) const;
};

// One row of a study's table: the tag of its variant and its values by column.
struct TableRow {
  std::string tag;
  std::map<std::string, double> values;
};

// One sweep of a configuration (probing amplitudes, or reversibility pre-strains): where it
// goes in results.h5 and its columns by name.
struct SweepColumns {
  ModuliOutputs::SweepMeta meta;
  std::map<std::string, std::vector<double>> columns;
};

// What the probes of one configuration return: its rows (one per probing tangential
// stiffness) and sweeps, and the file it was saved in (empty where the study saved none).
struct ConfigResults {
  std::string config;
  std::vector<TableRow> rows;
  std::vector<SweepColumns> sweeps;
};

// Scatter of K* and G* over the samples (seeds) of one preparation friction, size and target.
struct SizeScatter {
  double mu = 0, particles = 0, phi_target = 0;  // mu: NaN when the table has no such column
  int samples = 0;
  double K_mean = 0, K_std = 0, G_mean = 0, G_std = 0;  // std: sample standard deviation
};
// Groups the jammed rows of a study table by (mu_preparation, particles, phi_target). Empty
// when no group holds two samples: a study without repeated seeds has no scatter to report,
// and unjammed rows (no moduli) would only drag the means to zero.
std::vector<SizeScatter> size_scatter(const std::map<std::string, std::vector<double>>& table);

// Fingerprint (FNV-1a) of the scene parameters a moduli study used (key -> value text) that
// decide its results, so a checkpoint is only taken up by a run of the same scene.
std::string moduli_parameters_fingerprint(const std::map<std::string, std::string>& used);

// The checkpoint folder <out_dir>/variants of a study, created. Never drops hours of
// preparation silently: a fresh run (not `resume`) into an output folder whose variants/
// holds checkpoints of an unfinished study is refused, saying how to continue or restart.
std::string open_study_checkpoints(const std::string& out_dir, bool resume);

// <out_dir>/variants: where a study's checkpoints live (require_checkpoint_to_resume).
std::string study_checkpoints(const std::string& out_dir);

// Removes a finished study's checkpoint folder as one step: renamed out of the way first
// (a kill during the removal then leaves no half-emptied folder that --resume would read,
// only a hidden one the next run clears), then deleted.
void remove_study_checkpoints(const std::string& parts);

// <dir>/<name>.h5 holds the datasets, <dir>/<name>.index (written last) lists them with the
// fingerprint: a variant counts as finished only when its index exists.
void save_moduli_part(const std::string& dir, const std::string& name,
                      const std::string& fingerprint, const ModuliOutputs& part);
// True and `part` filled when a finished part with the same fingerprint exists; throws
// InputError naming the file when it belongs to other parameters.
bool load_moduli_part(const std::string& dir, const std::string& name,
                      const std::string& fingerprint, ModuliOutputs& part);

}  // namespace granular
