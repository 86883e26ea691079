#include "scenarios/common/scene_output.hpp"

#include "scenarios/common/charts.hpp"
#include "scenarios/common/run_report.hpp"

namespace granular {

SceneOutput::SceneOutput(const SceneFile& scene, const RunOptions& opts,
                         const std::string& scene_name, std::string chart_script)
    : scene_(scene),
      opts_(opts),
      scene_name_(scene_name),
      chart_script_(chart_script.empty() ? scene_name + ".py" : std::move(chart_script)) {}

Json& SceneOutput::summary() {
  if (!summary_open_) summary_ = scene_summary(scene_, scene_name_), summary_open_ = true;
  return summary_;
}

H5Writer& SceneOutput::h5() {
  if (committed_) throw std::logic_error(path("results.h5") + " was already committed");
  if (!h5_) h5_ = std::make_unique<H5Writer>(path("results.h5"));
  return *h5_;
}

void SceneOutput::commit_results() {
  h5().commit();
  committed_ = true;
}

void SceneOutput::finish(const std::vector<std::string>& tables) {
  if (h5_ && !committed_) commit_results();
  write_scene_summary(opts_, summary(), tables);
  if (opts_.charts && h5_) run_plot_script(chart_script_, path("results.h5"), opts_.out_dir);
}

}  // namespace granular
