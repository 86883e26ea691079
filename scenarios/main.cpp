// The `granular` command line: run or check a scene, print versions.
#include <CLI/CLI.hpp>
#include <Kokkos_Core.hpp>
#include <filesystem>
#include <iostream>

#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"
#include "core/run/ensemble.hpp"
#include "core/run/error.hpp"
#include "core/run/kernel_times.hpp"
#include "core/run/progress.hpp"
#include "granular_config.hpp"
#include "kernels/cpu/force_slabs.hpp"
#include "scenarios/common/run_report.hpp"
#include "scenarios/common/scene_keys.hpp"
#include "scenarios/moduli/moduli_theory.hpp"
#include "scenarios/scene_registry.hpp"

namespace {

std::string version_line() {
  const int v = KOKKOS_VERSION;
  return std::string("granular ") + GRANULAR_VERSION + "\nkokkos " + std::to_string(v / 10000) +
         "." + std::to_string(v / 100 % 100) + "." + std::to_string(v % 100) +
         " backends: " + granular::kokkos_backends() +
         "\ndefault execution space: " + Kokkos::DefaultExecutionSpace::name();
}

// What the command line asked for.
struct Options {
  bool show_version = false;
  std::string scene_path, out_dir, check_path, keys_scene;
  int threads = 0, force_slabs = 0;
  bool quiet = false, resume = false, kernel_times = false, keys_json = false;
  double stop_after_minutes = 0, max_hours = granular::Progress::budget_hours();
  granular::TheoryInput theory;
};

struct Subcommands {
  CLI::App *run, *check, *list, *keys, *theory;
};

void add_run_options(CLI::App& run, Options& o) {
  run.add_option("scene", o.scene_path, "scene file (TOML)")->required()->check(CLI::ExistingFile);
  run.add_option("--out", o.out_dir, "output directory (default out/<scene file name>)");
  run.add_option("--threads", o.threads, "host threads (default: all cores)")
      ->check(CLI::PositiveNumber);
  run.add_flag("--quiet", o.quiet, "no progress lines");
  run.add_flag("--resume", o.resume, "continue from the checkpoint in the output directory");
  run.add_flag("--kernel-times", o.kernel_times,
               "write kernel_times.json beside the results: wall seconds per kernel and per "
               "phase of the run (docs/speed.md)");
  run.add_option("--stop-after-minutes", o.stop_after_minutes,
                 "stop at the first checkpoint after this wall time (elastic_moduli); "
                 "continue with --resume")
      ->check(CLI::NonNegativeNumber);
  run.add_option("--max-hours", o.max_hours,
                 "wall-time budget of each phase: one projected to last longer stops early "
                 "with the estimate (0: no limit)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  run.add_option("--force-slabs", o.force_slabs,
                 "slabs of the host force pass (default 6; a third of them run at once: with "
                 "more than two threads use 3 x threads; changes the last bits of the sums)")
      ->check(CLI::Range(3, 100000));
}

void add_theory_options(CLI::App& theory, granular::TheoryInput& tin) {
  theory.add_option("--phi", tin.phi, "volume fraction")->required()->check(CLI::Range(0.0, 1.0));
  theory.add_option("--z", tin.z, "corrected coordination number")
      ->required()
      ->check(CLI::PositiveNumber);
  theory.add_option("--chi", tin.chi, "contact-number fluctuation (default: closure 1/(phi Z))");
  theory.add_option("--kt-kn", tin.kt_kn, "tangential over normal stiffness (default 0)");
  theory.add_option("--D", tin.D,
                    "size moment <d^2>/<d^3> x dbar (default 26/30 = 0.867: d uniform in [1, 3])");
}

Subcommands add_subcommands(CLI::App& app, Options& o) {
  Subcommands c;
  app.add_flag("--version", o.show_version, "print project and Kokkos versions and backends");
  c.run = app.add_subcommand("run", "run a scene file");
  add_run_options(*c.run, o);
  c.check = app.add_subcommand("check", "read and check every key of a scene file, run nothing");
  c.check->add_option("scene", o.check_path, "scene file (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  c.list = app.add_subcommand("scenes", "list the scene drivers");
  c.keys = app.add_subcommand(
      "keys", "every key a scene reads: kind, default, checked rules, example, meaning");
  c.keys->add_option("scene", o.keys_scene, "scene name (its shipped files) or scene file")
      ->required();
  c.keys->add_flag("--json", o.keys_json, "as JSON (a schema of the scene's keys)");
  c.theory = app.add_subcommand("theory", "EMT and fluctuation-theory moduli (JSON)");
  add_theory_options(*c.theory, o.theory);
  return c;
}

void print_theory(const granular::TheoryInput& tin) {
  const auto r = granular::moduli_theory(tin);
  granular::Json j = granular::Json::object();
  j["phi"] = tin.phi, j["z"] = tin.z, j["chi"] = r.chi, j["chi_from_closure"] = tin.chi < 0;
  j["kt_kn"] = tin.kt_kn, j["D"] = tin.D;
  j["rho"] = r.rho, j["zeta"] = r.zeta, j["rho_star"] = r.rho_s, j["zeta_star"] = r.zeta_s;
  j["K_emt"] = r.K_emt, j["G_emt"] = r.G_emt;
  j["K_ft_first_ring"] = r.K_ft1, j["G_ft_first_ring"] = r.G_ft1;
  j["K_ft_second_ring"] = r.K_ft2, j["G_ft_second_ring"] = r.G_ft2;
  std::cout << j.dump();
}

void initialize_kokkos(const Options& o, bool announce_slabs) {
  Kokkos::InitArguments args;
  args.num_threads = o.threads > 0 ? o.threads : -1;
  args.disable_warnings = true;  // OMP_PROC_BIND advice is for benchmarks, not for users
#ifdef KOKKOS_ENABLE_CUDA
  // One device per rank: the ranks of a machine take its GPUs in turn.
  int devices = 0;
  if (granular::ensemble::size() > 1 && cudaGetDeviceCount(&devices) == cudaSuccess && devices > 0)
    args.device_id = granular::ensemble::local_rank() % devices;
#endif
  Kokkos::initialize(args);
  if (o.force_slabs > 0) granular::default_force_slabs() = o.force_slabs;
#ifndef KOKKOS_ENABLE_CUDA
  const int host_threads = Kokkos::DefaultHostExecutionSpace().concurrency();
  if (announce_slabs && host_threads > granular::default_force_slabs() / 3)
    std::cerr << "note: the force pass splits the box into " << granular::default_force_slabs()
              << " slabs, " << granular::default_force_slabs() / 3 << " at a time; with "
              << host_threads << " threads add --force-slabs " << 3 * host_threads
              << " (the sums then differ in their last bits)\n";
#else
  (void)announce_slabs;
#endif
}

int print_keys(const Options& o) {
  try {
    const granular::SceneKeys k = granular::scene_keys(o.keys_scene);
    std::cout << (o.keys_json ? k.json().dump() + "\n" : k.table());
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
}

// Rank 0 runs the scene with its run record and report; the other ranks run their share of
// an ensemble or wait.
void run_scene_file(const Options& o, bool checking) {
  const std::string& scene_path = checking ? o.check_path : o.scene_path;
  auto scene = granular::SceneFile::load(scene_path);
  const granular::SceneEntry& entry = granular::find_scene(scene);
  granular::RunOptions opts;
  opts.out_dir =
      o.out_dir.empty() ? "out/" + std::filesystem::path(scene_path).stem().string() : o.out_dir;
  opts.progress = !o.quiet;
  opts.resume = o.resume;
  opts.stop_after_minutes = o.stop_after_minutes;
  granular::Progress::set_budget_hours(o.max_hours);
  opts.check_only = checking;
  if (checking) {
    entry.run(scene, opts);
    if (granular::ensemble::root())
      std::cout << scene_path << ": every key read and checked (" << entry.name << ")\n";
  } else if (granular::ensemble::root()) {
    if (o.kernel_times) granular::kernel_times::start();
    granular::run_scene(entry, scene, opts);  // the driver, then the run record and report
    std::cout << "results in " << opts.out_dir << "\n";
    if (o.kernel_times) {
      granular::kernel_times::stop();
      const std::string path = opts.out_dir + "/kernel_times.json";
      granular::write_text_file(path, granular::kernel_times::json().dump() + "\n");
      std::cout << "kernel times in " << path << "\n";
    }
  } else if (entry.spreads_over_ranks) {
    entry.run(scene, opts);  // its share of the units; rank 0 writes every output
  } else if (granular::ensemble::rank() == 1) {
    std::cerr << "scene " << entry.name << " is one simulation, not an ensemble: rank 0 runs "
              << "it alone and the other ranks wait (ensembles: chain_impulse, "
                 "chain_master_equation, elastic_moduli, mixture_moduli)\n";
  }
}

// The exit status of a run: 2 for bad input, 3 for a run stopped by a physics guard, 1 else.
int run_with_exit_status(const Options& o, bool checking) {
  const std::string& scene_path = checking ? o.check_path : o.scene_path;
  try {
    run_scene_file(o, checking);
    return 0;
  } catch (const granular::InputError& e) {
    // Every refusal names the scene file: those raised below the drivers (a file the scene
    // names, a derived quantity) may not know it.
    const std::string what = e.what();
    const bool named = what.find(scene_path) != std::string::npos;
    granular::ensemble::say(granular::ensemble::prefix() +
                            "error: " + (named ? what : "scene file " + scene_path + ": " + what));
    return 2;
  } catch (const granular::PhysicsError& e) {
    granular::ensemble::say(granular::ensemble::prefix() + "stopped: " + e.what());
    return 3;
  } catch (const std::exception& e) {
    granular::ensemble::say(granular::ensemble::prefix() + "error: " + e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  granular::ensemble::initialize(&argc, &argv);
  CLI::App app{"granular: elasticity and wave propagation of granular materials"};
  app.require_subcommand(0, 1);
  Options o;
  const Subcommands c = add_subcommands(app, o);
  CLI11_PARSE(app, argc, argv);
  if (o.show_version) {
    std::cout << version_line() << "\n";
    return 0;
  }
  if (c.list->parsed()) {
    for (const auto& e : granular::scene_registry())
      std::cout << e.name << "\t" << e.description << "\n";
    return 0;
  }
  if (c.theory->parsed()) {
    print_theory(o.theory);
    return 0;
  }
  if (!c.run->parsed() && !c.check->parsed() && !c.keys->parsed()) {
    std::cout << app.help();
    return 0;
  }
  initialize_kokkos(o, granular::ensemble::root() && c.run->parsed() && !o.quiet);
  if (c.keys->parsed()) {
    const int rc = print_keys(o);
    Kokkos::finalize();
    return rc;
  }
  const int rc = run_with_exit_status(o, c.check->parsed());
  // One rank's failure ends the whole run (no rank waits forever for a message); its
  // outputs stay checkpoints and partial files, never files that look finished.
  if (rc != 0 && granular::ensemble::size() > 1) {
    granular::ensemble::say("rank " + std::to_string(granular::ensemble::rank()) + " of " +
                            std::to_string(granular::ensemble::size()) +
                            " failed: stopping every rank");
    granular::ensemble::abort_all(rc);
  }
  Kokkos::finalize();
  granular::ensemble::finalize();
  return rc;
}
