// Every shipped scene file, mutated at random (values made hostile, lines dropped, keys
// misspelt or repeated, tables renamed, bytes garbled, the file cut short), is read and
// checked by its driver in check mode: each mutant must either pass or be refused with an
// InputError that names the file. Any other exception, a crash or a hang fails the test.
// The default suite checks a few hundred mutants; GRANULAR_FUZZ_MUTANTS (per scene file)
// turns it into a long run, e.g. GRANULAR_FUZZ_MUTANTS=500 for about 25 000 mutants.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "core/run/error.hpp"
#include "granular_config.hpp"
#include "scenarios/scene_registry.hpp"
#include "tests/test_support.hpp"

using namespace granular;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = text.find('\n', start);
    if (end == std::string::npos) {
      lines.push_back(text.substr(start));
      break;
    }
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string text;
  for (size_t i = 0; i < lines.size(); ++i) text += lines[i] + (i + 1 < lines.size() ? "\n" : "");
  return text;
}

bool is_assignment(const std::string& line) {
  const auto eq = line.find('=');
  return eq != std::string::npos && !line.empty() && line[0] != '#' && line[0] != '[';
}

// Values that have broken parsers and drivers elsewhere: wrong types, non-finite and extreme
// numbers, sizes past an int, empty and nested arrays.
const char* const kHostileValues[] = {"nan",
                                      "inf",
                                      "-inf",
                                      "-1",
                                      "0",
                                      "-0.0",
                                      "1e308",
                                      "1e-320",
                                      "9223372036854775807",
                                      "-9223372036854775808",
                                      "2147483648",
                                      "\"\"",
                                      "\"x\"",
                                      "true",
                                      "[]",
                                      "[nan]",
                                      "[1e308, -1]",
                                      "[[1]]",
                                      "{}",
                                      "{ a = 1 }",
                                      "0.5",
                                      "1",
                                      "3",
                                      "1e6",
                                      "-1e6",
                                      "[0, 0, 0]",
                                      "[1, \"a\"]"};

// One mutant of `text`, drawn from the stream `rng`; `what` says what was done.
std::string mutate(const std::string& text, std::mt19937_64& rng, std::string& what) {
  std::vector<std::string> lines = split_lines(text);
  std::vector<size_t> assignments;
  for (size_t i = 0; i < lines.size(); ++i)
    if (is_assignment(lines[i])) assignments.push_back(i);
  auto pick = [&](size_t n) { return static_cast<size_t>(rng() % std::max<size_t>(n, 1)); };
  const size_t a = assignments.empty() ? 0 : assignments[pick(assignments.size())];
  switch (rng() % 8) {
    case 0:
    case 1: {  // a hostile value (twice as likely: it reaches the drivers' checks)
      const std::string v = kHostileValues[pick(std::size(kHostileValues))];
      const std::string key = lines[a].substr(0, lines[a].find('='));
      what = "line " + std::to_string(a + 1) + " value -> " + v;
      lines[a] = key + "= " + v;
      break;
    }
    case 2:  // a key dropped
      what = "line " + std::to_string(a + 1) + " deleted";
      lines.erase(lines.begin() + static_cast<long>(a));
      break;
    case 3:  // a key misspelt
      what = "line " + std::to_string(a + 1) + " key misspelt";
      lines[a].insert(lines[a].find_first_of(" ="), "_x");
      break;
    case 4:  // a key repeated
      what = "line " + std::to_string(a + 1) + " repeated";
      lines.insert(lines.begin() + static_cast<long>(a), lines[a]);
      break;
    case 5: {  // a table renamed, or an unknown table added
      std::vector<size_t> headers;
      for (size_t i = 0; i < lines.size(); ++i)
        if (!lines[i].empty() && lines[i][0] == '[') headers.push_back(i);
      if (headers.empty()) {
        what = "table [bogus] added";
        lines.push_back("[bogus]\nvalue = 1");
      } else {
        const size_t h = headers[pick(headers.size())];
        what = "table at line " + std::to_string(h + 1) + " renamed";
        lines[h] = "[bogus" + std::to_string(h) + "]";
      }
      break;
    }
    case 6: {  // one byte garbled (control characters and invalid UTF-8 included)
      std::string t = join_lines(lines);
      const size_t at = pick(t.size());
      const char c = static_cast<char>(rng() % 256);
      what = "byte " + std::to_string(at) + " -> " + std::to_string(static_cast<unsigned char>(c));
      if (!t.empty()) t[at] = c;
      return t;
    }
    default: {  // the file cut short
      const std::string t = join_lines(lines);
      const size_t at = pick(t.size());
      what = "cut at byte " + std::to_string(at);
      return t.substr(0, at);
    }
  }
  return join_lines(lines);
}

enum class Outcome { Accepted, Refused, Broken };

// Checks one scene text the way `granular check` does; `problem` says what went wrong when
// the outcome is Broken.
Outcome check_text(const std::string& text, const std::string& path, std::string& problem) {
  RunOptions opts;
  opts.check_only = true, opts.progress = false, opts.charts = false;
  opts.out_dir = granular::testing::unique_temp_path("granular_fuzz_never_written").string();
  const std::string name = fs::path(path).filename().string();
  try {
    const SceneFile scene = SceneFile::parse(text, path);
    find_scene(scene).run(scene, opts);
    if (!fs::exists(opts.out_dir)) return Outcome::Accepted;
    problem = "check mode wrote " + opts.out_dir;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    if (msg.find(name) != std::string::npos) return Outcome::Refused;
    problem = "InputError without the file name: " + msg;
  } catch (const std::exception& e) {
    problem = std::string("not an InputError: ") + e.what();
  } catch (...) {
    problem = "unknown exception";
  }
  return Outcome::Broken;
}

std::vector<std::string> shipped_scene_files() {
  std::vector<std::string> files;
  for (const auto& path : granular::testing::shipped_scene_files()) files.push_back(path.string());
  return files;
}

// Scenes name their data files relative to the source tree (as the README's commands run
// them): check from there, and come back.
struct InSourceTree {
  fs::path before = fs::current_path();
  InSourceTree() { fs::current_path(GRANULAR_SOURCE_DIR); }
  ~InSourceTree() { fs::current_path(before); }
};

}  // namespace

TEST(SceneFileFuzz, EveryShippedSceneFilePassesCheckMode) {
  const InSourceTree here;
  const auto files = shipped_scene_files();
  ASSERT_GE(files.size(), 20u);
  for (const auto& f : files) {
    std::string problem;
    EXPECT_EQ(check_text(granular::testing::read_text(f), f, problem), Outcome::Accepted)
        << f << ": " << problem;
  }
}

TEST(SceneFileFuzz, MutatedSceneFilesAreAcceptedOrRefusedNamingTheFile) {
  const InSourceTree here;
  const char* env = std::getenv("GRANULAR_FUZZ_MUTANTS");
  const long per_file = env ? std::max(1L, std::atol(env)) : 8;
  const auto files = shipped_scene_files();
  long refused = 0, total = 0;
  for (size_t fi = 0; fi < files.size(); ++fi) {
    const std::string text = granular::testing::read_text(files[fi]);
    for (long k = 0; k < per_file; ++k) {
      // Each mutant's stream depends only on (file, k): a failure is reproduced by its pair.
      std::seed_seq seq{static_cast<std::uint32_t>(fi), static_cast<std::uint32_t>(k), 20261125u};
      std::mt19937_64 rng(seq);
      std::string what, problem;
      const std::string mutant = mutate(text, rng, what);
      const Outcome o = check_text(mutant, files[fi], problem);
      EXPECT_NE(o, Outcome::Broken)
          << files[fi] << " mutant " << k << " (" << what << "): " << problem;
      refused += o == Outcome::Refused;
      ++total;
    }
  }
  // Most mutations make a file wrong; if hardly any is refused, check mode is not reading
  // the keys and this test would prove nothing.
  EXPECT_GT(refused, total / 3) << refused << " of " << total << " mutants refused";
  std::cout << refused << " of " << total << " mutants refused, the rest accepted\n";
}
