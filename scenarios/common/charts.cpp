// The scenes' Python scripts (see charts.hpp).
#include "scenarios/common/charts.hpp"

#include <cstdlib>
#include <iostream>

#include "core/io/output.hpp"
#include "granular_config.hpp"

namespace granular {

std::string plot_script_path(const std::string& script) {
  std::string dir = GRANULAR_SOURCE_DIR "/scenarios/plots";
  if (const char* env = std::getenv("GRANULAR_PLOTS_DIR")) dir = env;
  return dir + "/" + script;
}

bool run_plot_script(const std::string& script, const std::string& h5, const std::string& outdir) {
  const bool ok = run_python_script(plot_script_path(script), {h5, outdir}, "charts");
  if (!ok) std::cerr << "note: the data is in " << h5 << "\n";
  return ok;
}

bool run_scene_script(const std::string& script, const std::vector<std::string>& args,
                      const std::string& what) {
  return run_python_script(plot_script_path(script), args, what);
}

}  // namespace granular
