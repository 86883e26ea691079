// Run record in summary.json and report.html (see run_report.hpp).
#include "scenarios/common/run_report.hpp"

#include <sys/utsname.h>
#include <unistd.h>

#include <Kokkos_Core.hpp>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "core/run/ensemble.hpp"
#include "core/run/error.hpp"
#include "granular_commit.hpp"
#include "granular_config.hpp"
#include "kernels/cpu/force_slabs.hpp"
#include "scenarios/common/charts.hpp"

namespace granular {
namespace fs = std::filesystem;

namespace {

std::string utc_text(std::time_t t) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// The processor's model name as Linux reports it ("" elsewhere): timings in a report mean
// little without it.
std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  return "";
}

// The run in progress under run_scene, for report_progress (one run per process at a time:
// the CLI runs one scene).
struct ActiveRun {
  bool on = false;
  bool summary_written = false;  // the driver wrote its summary.json (its results are whole)
  bool outputs_begun = false;    // the driver passed begin_outputs: it writes into dir
  std::string dir, scene, scene_file;
  std::chrono::steady_clock::time_point start, last_report;
  std::vector<std::string> earlier_parts;  // records of the parts before this one (--resume)
};
ActiveRun& active_run() {
  static ActiveRun run;
  return run;
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// A run continued with --resume is made of parts. Each part that ends before the run's end
// (stopped at a checkpoint or a time budget, or failed) leaves its run record as one line of
// <out>/run_parts.jsonl; the record of the part that completes the run lists them, with the
// wall time of all parts together, so that a study's record is not only its last part. A part
// killed outright (SIGKILL, the machine stopping) cannot write its line as it ends, so a long
// study keeps one for itself at each progress report, with the status "interrupted" and its
// wall time so far: what is left of it after a kill counts the part to its last report.
constexpr const char* kPartsFile = "run_parts.jsonl";

// Writes the parts file: the earlier parts, then `rec` as one line (written to a temporary
// name and renamed, so a kill leaves the previous file whole).
void write_parts(const std::string& dir, const std::vector<std::string>& earlier, const Json& rec) {
  std::string lines;
  for (const std::string& p : earlier) lines += p + "\n";
  std::string line = rec.dump(0);
  for (char& c : line)
    if (c == '\n') c = ' ';  // formatting only: JSON strings hold no raw newline
  try {
    write_text_file(dir + "/" + kPartsFile, lines + line + "\n");
  } catch (const std::exception& e) {  // never hides why the run ended
    std::cerr << "warning: " << kPartsFile << " not written: " << e.what() << "\n";
  }
}

std::vector<std::string> read_parts(const std::string& dir) {
  std::vector<std::string> parts;
  std::ifstream in(dir + "/" + kPartsFile);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) parts.push_back(line);
  return parts;
}

// "wall_time_s" of a record as run_record writes it (0 when absent).
double wall_time_of(const std::string& record) {
  const std::string key = "\"wall_time_s\":";
  const auto at = record.find(key);
  if (at == std::string::npos) return 0.0;
  try {
    return std::stod(record.substr(at + key.size()));
  } catch (const std::exception&) {
    return 0.0;
  }
}

// The earlier parts and the whole run's wall time, added to this part's record.
void add_earlier_parts(Json& rec, const std::vector<std::string>& parts, double wall_seconds) {
  if (parts.empty()) return;
  Json list = Json::array();
  double total = wall_seconds;
  for (const std::string& p : parts) list.push(Json::raw(p)), total += wall_time_of(p);
  rec["earlier_parts"] = list;
  rec["wall_time_all_parts_s"] = total;
}

}  // namespace

Json scene_summary(const SceneFile& scene, const std::string& name) {
  Json summary = Json::object();
  summary["scene"] = name;
  summary["scene_file"] = scene.path();
  Json& params = summary["parameters"];
  params = Json::object();
  for (const auto& [k, v] : scene.used()) params[k] = Json::raw(v);
  return summary;
}

std::string kokkos_backends() {
  std::string b;
#ifdef KOKKOS_ENABLE_CUDA
  b += " CUDA";
#endif
#ifdef KOKKOS_ENABLE_OPENMP
  b += " OpenMP";
#endif
#ifdef KOKKOS_ENABLE_SERIAL
  b += " Serial";
#endif
  return b.empty() ? b : b.substr(1);
}

Json run_record(double wall_seconds, const std::string& status, const std::string& message) {
  Json r = Json::object();
  r["status"] = status;
  if (!message.empty()) r["message"] = message;
  r["wall_time_s"] = wall_seconds;
  const std::time_t now = std::time(nullptr);
  r["started_utc"] = utc_text(now - static_cast<std::time_t>(wall_seconds + 0.5));
  r["finished_utc"] = utc_text(now);
  char host[256] = {0};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = 0;
  r["hostname"] = std::string(host);
  struct utsname u {};
  if (::uname(&u) == 0) r["system"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  r["cpu"] = cpu_model();
  r["cores"] = static_cast<int>(std::thread::hardware_concurrency());
  if (Kokkos::is_initialized())
    r["threads"] = static_cast<int>(Kokkos::DefaultHostExecutionSpace().concurrency());
  // MPI ranks the run was spread over (each with `threads` threads); hostname and threads
  // are rank 0's.
  r["ranks"] = ensemble::size();
  // The host force pass's slab count orders its sums (the last bits of every trajectory).
  r["force_slabs"] = default_force_slabs();
  r["execution_space"] = Kokkos::DefaultExecutionSpace::name();
  const int v = KOKKOS_VERSION;
  r["kokkos_version"] = std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." +
                        std::to_string(v % 100);
  r["kokkos_backends"] = kokkos_backends();
  r["granular_version"] = GRANULAR_VERSION;
  // The source commit the binary was built from ("-modified": tracked files differed).
  r["granular_commit"] = GRANULAR_COMMIT;
  return r;
}

void write_scene_summary(const RunOptions& opts, Json summary,
                         const std::vector<std::string>& tables) {
  ActiveRun& run = active_run();
  const bool recorded = run.on && run.dir == opts.out_dir;
  if (recorded) {
    const double wall = seconds_since(run.start);
    Json rec = run_record(wall, "complete", "");
    rec["scene"] = run.scene;
    rec["scene_file"] = run.scene_file;
    rec["summary_from_this_run"] = true;
    add_earlier_parts(rec, run.earlier_parts, wall);
    summary["run"] = rec;
  }
  write_summary(opts.out_dir + "/summary.json", summary, tables);
  if (recorded) run.summary_written = true;
}

bool write_report(const std::string& dir, const Json& run) {
  try {
    return run_scene_script("report.py", {dir, run.dump(0)}, "report");
  } catch (const std::exception& e) {
    std::cerr << "warning: report not written: " << e.what() << "\n";
    return false;
  }
}

void run_scene(const SceneEntry& entry, const SceneFile& scene, const RunOptions& opts) {
  // A run that never reaches begin_outputs wrote nothing (refused input, a check of the scene
  // file) and gets no report, so an earlier run's report stays as it was.
  ActiveRun& run = active_run();
  run.on = true;
  run.summary_written = false;
  run.outputs_begun = false;
  run.dir = opts.out_dir;
  run.scene = entry.name;
  run.scene_file = scene.path();
  run.start = std::chrono::steady_clock::now();
  run.last_report = run.start - std::chrono::hours(1);
  // A fresh run starts a new list of parts (an earlier run's file is replaced when this one
  // stops, and removed when it completes).
  run.earlier_parts = opts.resume ? read_parts(opts.out_dir) : std::vector<std::string>{};
  auto finish = [&](const std::string& status, const std::string& message) {
    run.on = false;
    if (!run.outputs_begun || !fs::is_directory(opts.out_dir)) return;
    const double wall = seconds_since(run.start);
    Json rec = run_record(wall, status, message);
    rec["scene"] = run.scene;
    rec["scene_file"] = run.scene_file;
    rec["summary_from_this_run"] = run.summary_written;
    const std::string parts_path = opts.out_dir + "/" + kPartsFile;
    if (status == "complete") {
      std::error_code ec;
      fs::remove(parts_path, ec);  // folded into summary.json's record
    } else {
      write_parts(opts.out_dir, run.earlier_parts, rec);
    }
    add_earlier_parts(rec, run.earlier_parts, wall);
    write_report(opts.out_dir, rec);
  };
  try {
    entry.run(scene, opts);
  } catch (const InputError&) {
    run.on = false;  // refused before it ran: an older report in the folder stays as it was
    throw;
  } catch (const std::exception& e) {
    finish("failed", e.what());
    throw;
  }
  // A driver that returns without writing its summary stopped at a checkpoint.
  if (!run.summary_written)
    finish("stopped",
           "the run stopped before its end (a checkpoint is kept): continue it with --resume");
  else
    finish("complete", "");
}

void note_outputs_begun(const RunOptions& opts) {
  ActiveRun& run = active_run();
  if (run.on && run.dir == opts.out_dir) run.outputs_begun = true;
}

void report_progress(const std::string& status) {
  ActiveRun& run = active_run();
  // A stage can be seconds long in a quick study: one report every few seconds is plenty.
  if (!run.on || seconds_since(run.last_report) < 10.0) return;
  run.last_report = std::chrono::steady_clock::now();
  Json rec = run_record(seconds_since(run.start), "running", status);
  rec["scene"] = run.scene;
  rec["scene_file"] = run.scene_file;
  rec["summary_from_this_run"] = false;
  write_report(run.dir, rec);
  // This part's line as it would stay if the part were killed now; the part's own end
  // replaces it (stopped, failed) or removes the file (complete).
  if (run.outputs_begun && fs::is_directory(run.dir)) {
    rec["status"] = "interrupted";
    rec["message"] = "the part ended without its own record (killed, or the machine stopped); " +
                     std::string("its wall time runs to its last progress report: ") + status;
    write_parts(run.dir, run.earlier_parts, rec);
  }
}

}  // namespace granular
