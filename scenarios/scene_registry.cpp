// Table of scene drivers known to the CLI.
#include "scenarios/scene_registry.hpp"

#include <filesystem>
#include <system_error>

#include "core/io/output.hpp"
#include "core/run/ensemble.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/run_report.hpp"

namespace granular {

const std::vector<SceneEntry>& scene_registry() {
  static const std::vector<SceneEntry> entries = {
      // DEM scenes
      {"two_particle_linear", "head-on collisions of two spheres, linear spring-dashpot",
       run_two_particle_linear},
      {"isotropic_compression", "isotropic compression of a polydisperse gas to a dense packing",
       run_isotropic_compression},
      {"hysteretic_collision", "head-on collisions with the hysteretic adhesive contact law",
       run_hysteretic_collision},
      {"impact",
       "sphere-wall or sphere-sphere impacts at any angle, spin and materials vs closed forms",
       run_impact},
      {"impact_benchmarks",
       "the eight published impact benchmark tests (Chung & Ooi 2011) vs their closed forms",
       run_impact_benchmarks},
      {"soft_collision", "three and five soft spheres colliding: classical, MC-strain, MC-stress",
       run_soft_collision},
      {"confined_compression",
       "soft balls in a rigid box compressed by the top wall: classical, MC-strain, MC-stress",
       run_confined_compression},
      {"elastic_moduli",
       "preparation protocol, unloading-branch configurations, elastic probing vs theory",
       run_elastic_moduli, true},
      {"mixture_moduli",
       "glass-rubber mixtures at target pressures: K, G, M, V_p against rubber fraction",
       run_mixture_moduli, true},
      // continuum law
      {"continuum_fit",
       "hypoelastic continuum law fitted to the moduli studies, checked on DEM paths",
       run_continuum_fit},
      // LAMMPS decks
      {"lammps_forces",
       "forces, torques and pair virial of LAMMPS' granular pair styles on a LAMMPS data file",
       run_lammps_forces},
      // signals and waves
      {"signal_analysis",
       "travel-time pickers, first-event spectra and spectral-ratio Q of recorded traces",
       run_signal_analysis},
      {"wave_transmission",
       "virtual transducers: a pulse through a confined packing, V_p and M against probing",
       run_wave_transmission},
      // chain scenes
      {"chain_impulse",
       "impulse on disordered granular chains: energy profile, spreading, localization",
       run_chain_impulse, true},
      {"chain_master_equation",
       "band-energy transfer matrix Q of disordered chains and the master-equation prediction",
       run_chain_master_equation, true},
      {"chain_tones",
       "standing-wave tones: space-time maps, band-energy curves, fit views, amplitude check",
       run_chain_tones},
  };
  return entries;
}

const SceneEntry& find_scene(const SceneFile& scene) {
  const std::string name = scene.text("scene");
  for (const auto& e : scene_registry())
    if (name == e.name) return e;
  std::string known;
  for (const auto& e : scene_registry()) known += std::string(" ") + e.name;
  throw InputError("scene file " + scene.path() + ": key 'scene' names an unknown scene '" + name +
                   "' (known:" + known + ")");
}

bool begin_outputs(const RunOptions& opts) {
  if (opts.check_only) return false;
  make_directories(opts.out_dir);
  note_outputs_begun(opts);
  // A run's outputs never sit beside an earlier run's: the earlier summary, report and
  // results go before anything new is written, so a run that stops or fails part-way leaves
  // no summary (nothing that looks finished) and no report of another run.
  // final_state.xdmf names datasets of results.h5: it goes first, so that a kill between the
  // two never leaves it pointing at a removed file.
  if (ensemble::root())
    for (const char* name : {"summary.json", "report.html", "final_state.xdmf", "results.h5"}) {
      std::error_code ec;
      std::filesystem::remove(opts.out_dir + "/" + name, ec);
    }
  return true;
}

void require_checkpoint_to_resume(const RunOptions& opts, const std::string& checkpoint) {
  if (!opts.resume || opts.check_only) return;
  namespace fs = std::filesystem;
  std::error_code ec;
  const bool there =
      fs::is_directory(checkpoint, ec) ? !fs::is_empty(checkpoint, ec) : fs::exists(checkpoint, ec);
  if (there) return;
  throw InputError("--resume: no checkpoint at " + checkpoint +
                   (fs::exists(opts.out_dir + "/summary.json", ec)
                        ? ": the run in " + opts.out_dir +
                              " has finished (its outputs are left as they are); run without "
                              "--resume to run it again"
                        : ": nothing was checkpointed there; run without --resume"));
}

}  // namespace granular
