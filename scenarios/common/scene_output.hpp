// The output context of one scene run: its folder, results.h5, summary.json and the charts,
// in the order every driver writes them. A driver opens it once its keys are read and
// checked (after begin_outputs), fills results.h5 and the summary, and ends with finish():
//
//   if (!begin_outputs(opts)) return;
//   SceneOutput out(scene, opts, "two_particle_linear");
//   write_quantity(out.h5(), "/table/restitution", e, "1");
//   out.summary()["max_rel_error_restitution"] = worst;
//   out.finish();  // results.h5 renamed into place, summary.json with the run record, charts
//
// A driver that returns without finish() (stopped at a checkpoint, or an exception) leaves
// no results.h5 and no summary.json of this run: the partial results file is removed, and the
// run counts as stopped (scenarios/common/run_report.hpp).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

class SceneOutput {
 public:
  // `scene_name` opens summary.json (scene_summary) and names the chart script
  // scenarios/plots/<scene_name>.py unless `chart_script` names another one.
  SceneOutput(const SceneFile& scene, const RunOptions& opts, const std::string& scene_name,
              std::string chart_script = "");
  SceneOutput(const SceneOutput&) = delete;
  SceneOutput& operator=(const SceneOutput&) = delete;

  // <out_dir>/<name>.
  std::string path(const std::string& name) const { return opts_.out_dir + "/" + name; }

  // results.h5, built under a hidden name until it is committed (on first use).
  H5Writer& h5();
  // Renames results.h5 into place now, for outputs that point into it before the run ends
  // (an XDMF sidecar); finish() does it otherwise.
  void commit_results();
  // summary.json as it will be written: the scene, its file and every key used so far (taken
  // at the first call, so that a key read later is not listed), then the driver's results.
  Json& summary();

  // Ends the run's outputs: commits results.h5 (when written and not yet committed), writes
  // summary.json with the run record (`tables`: members whose cells may be null, see
  // write_summary), then draws the charts from results.h5 when the run asks for charts.
  void finish(const std::vector<std::string>& tables = {});

 private:
  const SceneFile& scene_;
  const RunOptions& opts_;
  std::string scene_name_, chart_script_;
  std::unique_ptr<H5Writer> h5_;
  bool committed_ = false;
  bool summary_open_ = false;
  Json summary_;
};

}  // namespace granular
