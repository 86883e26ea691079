// The scenes' Python scripts (charts, report.html): where they live and how a scene runs
// them. They sit in scenarios/plots of the source tree the binary was built from, or in
// $GRANULAR_PLOTS_DIR (an empty folder there turns charts and reports off).
#pragma once
#include <string>
#include <vector>

namespace granular {

// The path of scenarios/plots/<script> (or $GRANULAR_PLOTS_DIR/<script>).
std::string plot_script_path(const std::string& script);

// Runs the chart script <script> on <h5> into <outdir>. A missing interpreter or a failing
// script is reported, not fatal: the data is kept.
bool run_plot_script(const std::string& script, const std::string& h5, const std::string& outdir);

// Runs <script> of the plots folder with `args` (the report); see run_python_script.
bool run_scene_script(const std::string& script, const std::vector<std::string>& args,
                      const std::string& what);

}  // namespace granular
