// report.html of a run: written by the CLI's run path for a tiny two-particle run, it embeds
// every chart of the folder, lists the scene's parameters, links the data files and needs no
// network; summary.json gains the run record (wall time, machine). A missing report script
// never fails the run, and a refused run leaves an earlier report alone. When Debian's
// `chromium` is installed, the page is opened headless: every image must decode and nothing
// may raise an error on the console.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>

#include "core/io/scene_file.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/run_report.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/external_program.hpp"
#include "tests/test_support.hpp"

using namespace granular;
using granular::testing::read_text;
namespace fs = std::filesystem;

namespace {

std::string base64(const std::string& bytes) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16 |
                       static_cast<unsigned char>(bytes[i + 1]) << 8 |
                       static_cast<unsigned char>(bytes[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += abc[(v >> s) & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += abc[(v >> 18) & 63];
    out += abc[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? abc[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

const SceneEntry& entry_named(const std::string& name) {
  for (const auto& e : scene_registry())
    if (name == e.name) return e;
  throw std::runtime_error("no scene " + name);
}

// The scene `text`, written to `path` and read back as a run reads it.
SceneFile scene_written(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  SceneFile scene = SceneFile::load(path);
  scene.text("scene");
  return scene;
}

// The shipped isotropic compression with a time step its guard refuses once the run has begun
// its outputs (the system is built after begin_outputs).
SceneFile too_fast_compression(const std::string& dir) {
  std::string text = granular::testing::shipped_scene("isotropic_compression.toml");
  granular::testing::replace_once(text, "dt = 0.004", "dt = 0.4");
  return scene_written(dir + "/too_fast.toml", text);
}

// One small two-particle run through the CLI's path (driver, run record, report), shared by
// the tests of this file.
class RunReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = granular::testing::temp_dir("run_report");
    fs::create_directories(dir_);
    std::string text = granular::testing::shipped_scene("two_particle_linear.toml");
    granular::testing::replace_once(text, "impact_speeds = [0.001, 0.01, 0.1]",
                                    "impact_speeds = [0.01, 0.1]");
    granular::testing::replace_once(text, "steps_per_contact = 1000", "steps_per_contact = 200");
    scene_path_ = dir_ + "/two_particle_linear.toml";
    std::ofstream(scene_path_) << text;
    RunOptions opts;
    opts.out_dir = dir_ + "/out";
    opts.progress = false;
    run_scene(entry_named("two_particle_linear"), scene(), opts);
  }
  // The scene file as the CLI hands it to a driver: its `scene` key already read.
  static SceneFile scene() {
    SceneFile s = SceneFile::load(scene_path_);
    s.text("scene");
    return s;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string out() { return dir_ + "/out"; }
  static std::string dir_, scene_path_;
};
std::string RunReport::dir_, RunReport::scene_path_;

// summary.json (`js`) of a run made of two parts: its earlier_parts holds the first part, with
// `status`, and wall_time_all_parts_s is the second part's wall time plus the first's (its
// line of run_parts.jsonl, `parts`).
void expect_earlier_part_summed(const std::string& js, const std::string& parts,
                                const std::string& status) {
  const auto at = js.find("\"earlier_parts\"");
  ASSERT_NE(at, std::string::npos) << js;
  EXPECT_NE(js.find("\"status\": \"" + status + "\"", at), std::string::npos) << js;
  std::smatch m;
  const std::string tail = js.substr(js.find("\"run\": {"));
  ASSERT_TRUE(std::regex_search(tail, m, std::regex("\"wall_time_s\": ([0-9.eE+-]+)")));
  const double last = std::stod(m[1]);
  ASSERT_TRUE(std::regex_search(js, m, std::regex("\"wall_time_all_parts_s\": ([0-9.eE+-]+)")));
  const double all = std::stod(m[1]);
  ASSERT_TRUE(std::regex_search(parts, m, std::regex("\"wall_time_s\": ([0-9.eE+-]+)")));
  EXPECT_NEAR(all, last + std::stod(m[1]), 1e-6 * all + 1e-12);
}

}  // namespace

TEST_F(RunReport, SummaryRecordsWallTimeAndMachine) {
  const std::string js = read_text(out() + "/summary.json");
  EXPECT_NE(js.find("\"run\": {"), std::string::npos) << js;
  for (const char* key : {"wall_time_s", "hostname", "cores", "threads", "execution_space",
                          "kokkos_backends", "status"})
    EXPECT_NE(js.find(std::string("\"") + key + "\""), std::string::npos) << key;
  EXPECT_NE(js.find("\"status\": \"complete\""), std::string::npos);
  // The source commit of the binary: 40 hex digits (with "-modified" when tracked files
  // differed from it), or "unknown" outside a git clone.
  const std::regex commit("\"granular_commit\": \"([0-9a-f]{40}(-modified)?|unknown)\"");
  EXPECT_TRUE(std::regex_search(js, commit)) << js;
  EXPECT_EQ(js.substr(js.size() - 2), "}\n");
  // One record, written with the summary as its last member.
  EXPECT_EQ(js.find("\"run\": {"), js.rfind("\"run\": {"));
  EXPECT_GT(js.find("\"run\": {"), js.rfind("\"max_rel_momentum_change\""));
}

TEST_F(RunReport, ReportEmbedsEveryChartListsParametersAndLinksTheData) {
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3: no report";
  const std::string html = read_text(out() + "/report.html");
  ASSERT_FALSE(html.empty()) << "report.html missing";
  EXPECT_NE(html.find("<meta name=\"viewport\""), std::string::npos);
  EXPECT_NE(html.find("<h1>two_particle_linear</h1>"), std::string::npos);
  // Every PNG of the folder, embedded byte for byte.
  int pngs = 0;
  for (const auto& f : fs::directory_iterator(out())) {
    if (f.path().extension() != ".png") continue;
    ++pngs;
    const std::string uri = "data:image/png;base64," + base64(read_text(f.path().string()));
    EXPECT_NE(html.find(uri), std::string::npos) << f.path() << " is not embedded";
  }
  size_t images = 0;
  for (size_t at = html.find("<img"); at != std::string::npos; at = html.find("<img", at + 1))
    ++images;
  EXPECT_EQ(images, static_cast<size_t>(pngs));
  // The parameters table: every key the scene read, with the scene file's note on kn.
  EXPECT_NE(html.find("<h2>Parameters</h2>"), std::string::npos);
  for (const char* key :
       {"contact.kn", "contact.gamma_n", "particles.density", "particles.diameter",
        "particles.partner_diameters", "collisions.impact_speeds", "collisions.steps_per_contact"})
    EXPECT_NE(html.find(std::string("<code>") + key + "</code>"), std::string::npos) << key;
  EXPECT_NE(html.find("normal stiffness (1e8 N/m)"), std::string::npos);
  // Results as tables, the run's wall time, links to the data.
  EXPECT_NE(html.find("<h2>Results</h2>"), std::string::npos);
  EXPECT_NE(html.find("wall time"), std::string::npos);
  EXPECT_NE(html.find("href=\"results.h5\""), std::string::npos);
  EXPECT_NE(html.find("href=\"summary.json\""), std::string::npos);
  // Self-contained: nothing is fetched (no external source, style sheet or script).
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_FALSE(fs::exists(out() + "/.report.html.partial"));
}

TEST_F(RunReport, MissingReportScriptDoesNotFailTheRun) {
  const std::string empty = dir_ + "/no_scripts";
  fs::create_directories(empty);
  RunOptions opts;
  opts.out_dir = dir_ + "/out_no_report";
  opts.progress = false;
  opts.charts = false;
  ::setenv("GRANULAR_PLOTS_DIR", empty.c_str(), 1);
  EXPECT_NO_THROW(run_scene(entry_named("two_particle_linear"), scene(), opts));
  ::unsetenv("GRANULAR_PLOTS_DIR");
  EXPECT_TRUE(fs::exists(opts.out_dir + "/summary.json"));
  EXPECT_FALSE(fs::exists(opts.out_dir + "/report.html"));
}

TEST_F(RunReport, RefusedRunLeavesTheEarlierReportAlone) {
  const auto before = fs::last_write_time(out() + "/report.html");
  const std::string bad = dir_ + "/bad.toml";
  std::ofstream(bad) << read_text(scene_path_) << "\n[extra]\nunknown_key = 1\n";
  SceneFile scene = SceneFile::load(bad);
  scene.text("scene");
  RunOptions opts;
  opts.out_dir = out();
  opts.progress = false;
  EXPECT_THROW(run_scene(entry_named("two_particle_linear"), scene, opts), InputError);
  EXPECT_EQ(fs::last_write_time(out() + "/report.html"), before);
}

// The report follows the driver's begin_outputs, not the folder's file times: a run that fails
// after it began its outputs, before it wrote any file into an empty folder it did not have to
// create, still gets a report saying it failed (the folder's time did not change, and an
// earlier version wrote no report then).
TEST_F(RunReport, RunThatFailsBeforeWritingAnyFileGetsAFailedReport) {
  const std::string folder = dir_ + "/out_failed_empty";
  fs::create_directories(folder);
  SceneFile scene = too_fast_compression(dir_);
  RunOptions opts;
  opts.out_dir = folder;
  opts.progress = false, opts.charts = false;
  EXPECT_THROW(run_scene(entry_named("isotropic_compression"), scene, opts), PhysicsError);
  ASSERT_TRUE(fs::exists(folder + "/report.html"));
  EXPECT_NE(read_text(folder + "/report.html").find("failed"), std::string::npos);
  EXPECT_FALSE(fs::exists(folder + "/summary.json"));
}

// Opens a copy of the report in headless Chromium with a probe that writes, once the page
// has loaded, how many images decoded (naturalWidth > 0) and how many errors were raised
// (script errors, failed loads, console.error) into the DOM that --dump-dom prints.
TEST_F(RunReport, ChromiumLoadsEveryImageWithoutConsoleErrors) {
  const std::string chromium = granular::testing::find_program("chromium");
  if (chromium.empty())
    GTEST_SKIP() << "chromium is not installed (Debian package `chromium`): report not opened "
                    "in a browser";
  std::string html = read_text(out() + "/report.html");
  ASSERT_FALSE(html.empty());
  const std::string probe =
      "<script>var errors=0;"
      "window.addEventListener('error',function(){errors++;},true);"
      "var ce=console.error;console.error=function(){errors++;ce.apply(console,arguments);};"
      "window.addEventListener('load',function(){var im=document.images,ok=0;"
      "for(var i=0;i<im.length;i++)if(im[i].complete&&im[i].naturalWidth>0)ok++;"
      "var d=document.createElement('pre');d.id='probe';"
      "d.textContent='images '+ok+'/'+im.length+' errors '+errors;"
      "document.body.appendChild(d);});</script>";
  // The probe goes first in <head> so it sees errors raised while the page loads.
  const auto head = html.find("<head>");
  ASSERT_NE(head, std::string::npos);
  html.insert(head + 6, probe);
  const std::string page = dir_ + "/probe.html", dump = dir_ + "/dom.txt";
  std::ofstream(page) << html;
  const int rc = granular::testing::run_program(
      {chromium, "--headless", "--disable-gpu", "--no-sandbox", "--no-first-run",
       "--user-data-dir=" + dir_ + "/chromium-profile", "--virtual-time-budget=10000", "--dump-dom",
       "file://" + page},
      dump);
  const std::string dom = read_text(dump);
  ASSERT_EQ(rc, 0) << dom;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom, m, std::regex("images (\\d+)/(\\d+) errors (\\d+)")))
      << "the probe did not run:\n"
      << dom.substr(0, 2000);
  EXPECT_EQ(m[1].str(), m[2].str()) << "images that did not decode";
  EXPECT_GT(std::stoi(m[2].str()), 0);
  EXPECT_EQ(m[3].str(), "0") << "errors on the console";
}

// A new run into a folder that holds an earlier run's outputs removes them before it writes
// anything: a run that fails part-way leaves no summary, and neither the earlier summary nor
// its report beside files of its own (a full disk used to leave a new results.h5 beside the
// earlier summary.json).
TEST_F(RunReport, FailedRunLeavesNoEarlierRunsSummaryOrReport) {
  const std::string folder = dir_ + "/out_failed";
  fs::create_directories(folder);
  for (const char* name : {"summary.json", "report.html", "results.h5"})
    std::ofstream(folder + "/" + name) << "earlier run\n";
  SceneFile scene = too_fast_compression(dir_);
  RunOptions opts;
  opts.out_dir = folder;
  opts.progress = false, opts.charts = false;
  EXPECT_THROW(run_scene(entry_named("isotropic_compression"), scene, opts), PhysicsError);
  EXPECT_FALSE(fs::exists(folder + "/summary.json"));
  EXPECT_FALSE(fs::exists(folder + "/results.h5"));
  // A report, where one is written, describes this failed run, not the earlier one.
  if (fs::exists(folder + "/report.html")) {
    const std::string html = read_text(folder + "/report.html");
    EXPECT_EQ(html.find("earlier run"), std::string::npos);
    EXPECT_NE(html.find("failed"), std::string::npos);
  }
}

// The report script meets a write error (a full disk, here a folder in the way of its
// temporary file) with one line that names the file, not a Python traceback, and leaves no
// report behind.
TEST_F(RunReport, ReportThatCannotBeWrittenSaysSoInOneLine) {
  const std::string folder = dir_ + "/out_unwritable";
  fs::create_directories(folder + "/.report.html.partial");
  fs::copy_file(out() + "/summary.json", folder + "/summary.json");
  const std::string log = dir_ + "/report_error.txt";
  const int rc = granular::testing::run_program(
      {"/usr/bin/python3", std::string(GRANULAR_SOURCE_DIR) + "/scenarios/plots/report.py", folder},
      log);
  const std::string said = read_text(log);
  EXPECT_EQ(rc, 1) << said;
  EXPECT_EQ(said.find("Traceback"), std::string::npos) << said;
  EXPECT_NE(said.find("report.html not written"), std::string::npos) << said;
  EXPECT_FALSE(fs::exists(folder + "/report.html"));
}

// A driver that returns without writing its summary stopped at a checkpoint: the run says so
// in its report (decided by the run, not by comparing file times), and leaves no summary.
TEST_F(RunReport, RunStoppedAtItsCheckpointIsReportedStoppedWithoutASummary) {
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3: no report";
  std::string text = granular::testing::small_isotropic_scene() + "stop_after = 1000\n";
  granular::testing::replace_once(text, "checkpoint_every = 2000", "checkpoint_every = 1000");
  SceneFile scene = scene_written(dir_ + "/stopped.toml", text);
  RunOptions opts;
  opts.out_dir = dir_ + "/out_stopped";
  opts.progress = false, opts.charts = false;
  run_scene(entry_named("isotropic_compression"), scene, opts);
  EXPECT_TRUE(fs::exists(opts.out_dir + "/checkpoint.h5"));
  EXPECT_FALSE(fs::exists(opts.out_dir + "/summary.json"));
  const std::string html = read_text(opts.out_dir + "/report.html");
  EXPECT_NE(html.find("Run stopped before its end."), std::string::npos) << html.substr(0, 2000);
  EXPECT_NE(html.find("continue it with --resume"), std::string::npos);
}

// A run continued with --resume: the record of the part that completes it lists the part that
// stopped (its status, its own wall time and commit) and the wall time of both together, so a
// study's record is not only its last part; the list of parts is folded into summary.json.
TEST_F(RunReport, ResumedRunRecordsEveryPartAndTheirTotalWallTime) {
  std::string text = granular::testing::small_isotropic_scene();
  granular::testing::replace_once(text, "checkpoint_every = 2000", "checkpoint_every = 1000");
  const std::string path = dir_ + "/parts.toml";
  std::ofstream(path) << text + "stop_after = 1000\n";
  RunOptions opts;
  opts.out_dir = dir_ + "/out_parts";
  opts.progress = false, opts.charts = false;
  auto run = [&]() {
    SceneFile scene = SceneFile::load(path);
    scene.text("scene");
    run_scene(entry_named("isotropic_compression"), scene, opts);
  };
  run();
  ASSERT_FALSE(fs::exists(opts.out_dir + "/summary.json"));
  const std::string parts = read_text(opts.out_dir + "/run_parts.jsonl");
  EXPECT_EQ(std::count(parts.begin(), parts.end(), '\n'), 1) << parts;
  EXPECT_NE(parts.find("\"status\": \"stopped\""), std::string::npos) << parts;

  std::ofstream(path) << text;  // the rest of the run, to its end
  opts.resume = true;
  run();
  const std::string js = read_text(opts.out_dir + "/summary.json");
  EXPECT_FALSE(fs::exists(opts.out_dir + "/run_parts.jsonl"));
  expect_earlier_part_summed(js, parts, "stopped");

  // A fresh run starts a new record: a parts file left in its folder is not its history.
  opts.resume = false;
  opts.out_dir = dir_ + "/out_parts_fresh";
  fs::create_directories(opts.out_dir);
  std::ofstream(opts.out_dir + "/run_parts.jsonl")
      << "{\"status\": \"stopped\", \"wall_time_s\": 9}\n";
  run();
  EXPECT_EQ(read_text(opts.out_dir + "/summary.json").find("earlier_parts"), std::string::npos);
  EXPECT_FALSE(fs::exists(opts.out_dir + "/run_parts.jsonl"));
}

namespace {

// A driver that reports progress once, keeps the parts file as a kill at that moment would
// leave it (parts_at_kill.jsonl beside its folder), and completes.
void driver_with_progress(const SceneFile&, const RunOptions& opts) {
  fs::create_directories(opts.out_dir);
  note_outputs_begun(opts);
  report_progress("stage 1 of 2 done");
  fs::copy_file(opts.out_dir + "/run_parts.jsonl", opts.out_dir + "/../parts_at_kill.jsonl",
                fs::copy_options::overwrite_existing);
  Json summary = Json::object();
  summary["scene"] = "progress_test";
  write_scene_summary(opts, summary);
}

}  // namespace

// A part killed outright (SIGKILL, the machine stopping) cannot write its record as it ends: a
// long study keeps an "interrupted" line for itself at each progress report, and the resume
// after the kill counts that part's wall time to its last report. A part that ends by itself
// leaves no such line behind.
TEST_F(RunReport, PartKilledAfterAProgressReportIsCountedWhenTheRunResumes) {
  const SceneEntry entry{"progress_test", "reports progress once", driver_with_progress};
  const std::string base = dir_ + "/out_killed";
  RunOptions opts;
  opts.out_dir = base + "/run";
  opts.progress = false, opts.charts = false;
  run_scene(entry, scene(), opts);
  EXPECT_FALSE(fs::exists(opts.out_dir + "/run_parts.jsonl"));  // complete: nothing left
  EXPECT_EQ(read_text(opts.out_dir + "/summary.json").find("earlier_parts"), std::string::npos);
  const std::string at_kill = read_text(base + "/parts_at_kill.jsonl");
  EXPECT_EQ(std::count(at_kill.begin(), at_kill.end(), '\n'), 1) << at_kill;
  EXPECT_NE(at_kill.find("\"status\": \"interrupted\""), std::string::npos) << at_kill;
  EXPECT_NE(at_kill.find("stage 1 of 2 done"), std::string::npos) << at_kill;

  // The folder as a kill after that report leaves it: the parts file, no summary.
  fs::remove(opts.out_dir + "/summary.json");
  fs::copy_file(base + "/parts_at_kill.jsonl", opts.out_dir + "/run_parts.jsonl");
  opts.resume = true;
  run_scene(entry, scene(), opts);
  EXPECT_FALSE(fs::exists(opts.out_dir + "/run_parts.jsonl"));
  const std::string js = read_text(opts.out_dir + "/summary.json");
  expect_earlier_part_summed(js, at_kill, "interrupted");
}
