// The record and the report of one run: wall time, machine and build go into summary.json
// (member "run"), and scenarios/plots/report.py turns the output folder into report.html
// (scene, parameters, results, every chart, links to the data), a static page that needs
// no network. A missing python3 or a failing report script never fails the run.
#pragma once
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

// The opening of every summary.json: {"scene": name, "scene_file": the path as given,
// "parameters": every key of the scene file that the driver used, with its text}. The driver
// adds its results after it and writes it with write_scene_summary.
Json scene_summary(const SceneFile& scene, const std::string& name);

// "OpenMP Serial", the Kokkos backends this build has.
std::string kokkos_backends();

// Wall time, dates, host, cores and threads, Kokkos and engine versions of a run that
// started `wall_seconds` ago; `status` is "complete", "stopped", "failed" or "running".
Json run_record(double wall_seconds, const std::string& status, const std::string& message);

// Writes <opts.out_dir>/summary.json (write_summary: nothing non-finite outside `tables`), the
// last output of a driver whose results are whole. Inside run_scene the run record (wall
// time so far, machine, build) is its member "run", and the run counts as complete; a
// driver that returns without calling it stopped at a checkpoint.
void write_scene_summary(const RunOptions& opts, Json summary,
                         const std::vector<std::string>& tables = {});

// Writes <dir>/report.html from what the folder holds now; false (with a note) when the
// report could not be written.
bool write_report(const std::string& dir, const Json& run);

// Runs a scene as the CLI does: the driver, then the run record in summary.json and the
// report. A run that stops early (a checkpoint, a failure) still gets a report saying so.
void run_scene(const SceneEntry& entry, const SceneFile& scene, const RunOptions& opts);

// Called by begin_outputs: the run in progress writes into its folder from here on, so it
// ends with a report, whatever stops it.
void note_outputs_begun(const RunOptions& opts);

// For long studies: rewrites the report of the run in progress with `status` (a stage just
// finished), at most once every few seconds, and this part's line of run_parts.jsonl as a kill
// would leave it ("interrupted", its wall time so far), so that a resume after a kill still
// counts the killed part. Does nothing outside run_scene (tests calling a driver directly).
void report_progress(const std::string& status);

}  // namespace granular
