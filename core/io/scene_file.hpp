// Scene (scenario) files: TOML with strict key checking. Every key a scene reads is
// recorded; keys that nobody read are reported as unknown, naming the key and the file.
#pragma once
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/run/error.hpp"

namespace granular {

class SceneFile {
 public:
  static SceneFile load(const std::string& path);
  static SceneFile parse(const std::string& text, const std::string& source_name);

  const std::string& path() const { return path_; }

  // Required values: a missing key or a value of the wrong type is an InputError. Numbers
  // must be finite (nan and inf are refused, naming the key): a non-finite input would only
  // surface later as a crash or as silent nonsense deep inside a run.
  double real(const std::string& key) const;
  // A number that may be +inf where infinity has a meaning (a rigid material's modulus);
  // nan and -inf are still refused.
  double real_or_infinite(const std::string& key) const;
  long integer(const std::string& key) const;
  // An integer that must fit an int (counts, indices): a larger value is refused naming the
  // key instead of being truncated by a cast.
  int small_integer(const std::string& key) const;
  std::string text(const std::string& key) const;
  bool flag(const std::string& key) const;
  std::vector<double> reals(const std::string& key) const;
  // A non-empty array of strings.
  std::vector<std::string> texts(const std::string& key) const;

  // Optional values with defaults (the default is recorded as the value used).
  double real(const std::string& key, double def) const;
  long integer(const std::string& key, long def) const;
  int small_integer(const std::string& key, int def) const;
  std::string text(const std::string& key, const std::string& def) const;
  bool flag(const std::string& key, bool def) const;
  std::vector<double> reals(const std::string& key, const std::vector<double>& def) const;
  // The same where an empty array is a meaningful choice (an empty list switches a part off).
  std::vector<double> reals_or_none(const std::string& key, const std::vector<double>& def) const;
  bool has(const std::string& key) const;
  // A path to an input the scene reads (a file, or a folder where `folder` is true). A relative
  // path is resolved from the folder of the scene file, so a scene copied together with its
  // inputs works from any working directory; the path must exist, which `granular check`
  // therefore checks too. The optional form returns "" when the key is absent.
  std::string input_path(const std::string& key, bool folder = false) const;
  std::string optional_input_path(const std::string& key, bool folder = false) const;
  // A named choice: `parse` turns the text of `key` (default `def`) into a value and throws
  // InputError for an unknown name; the error is re-thrown naming the key and the file.
  template <class Parse>
  auto choice(const std::string& key, const std::string& def, Parse parse) const {
    const std::string value = text(key, def);
    try {
      return parse(value);
    } catch (const InputError& e) {
      fail(key, e.what());
    }
  }
  // Names of the sub-tables of table `key`, sorted by name (e.g. the walls of [walls.floor],
  // [walls.top]); empty when the table is absent. A value that is not a table is an error.
  std::vector<std::string> tables(const std::string& key) const;

  // Throws naming the first key present in the file that no reader asked for.
  void reject_unknown_keys() const;

  // Every value read so far (key -> value as text), for summary.json.
  const std::map<std::string, std::string>& used() const { return used_; }

  // What the readers said of each key so far (`granular keys`): its kind (number, integer,
  // string, flag, numbers, strings), its default where it has one, and the rules checked
  // on it by require() (e.g. "must be positive").
  struct KeyFacts {
    std::string kind, default_value;
    bool has_default = false;
    std::vector<std::string> rules;
  };
  const std::map<std::string, KeyFacts>& facts() const { return facts_; }

  // A range check with the same style of message.
  void require(bool ok, const std::string& key, const std::string& what) const;
  // A list whose entries name outputs (variants, models, targets) must not repeat one: the
  // run would otherwise go to its end and fail writing the second dataset of that name.
  void require_distinct(const std::string& key, const std::vector<double>& values) const;
  // Refuses, before anything is allocated, a size set by `key` whose run would need more
  // than the memory this machine has available (`bytes`: an estimate of that need).
  void require_memory(const std::string& key, double bytes) const;
  // A count (particles, beads, samples): an integer >= `min` that fits an int and whose run,
  // at `bytes_each` per item, fits in the available memory; all checked before allocating.
  int count(const std::string& key, long min, double bytes_each) const;

 private:
  struct Document;  // the parsed TOML tree; kept out of this header so device compilers
                    // never see the TOML library
  const void* find(const std::string& key) const;
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  void note(const std::string& key, const std::string& value) const;
  void kind(const std::string& key, const char* kind) const;
  void offer(const std::string& key, const std::string& default_value) const;
  // An array of numbers as the file gives it, noted when not empty.
  std::vector<double> reals_in_file(const std::string& key) const;
  std::vector<double> reals_with_default(const std::string& key, const std::vector<double>& def,
                                         bool may_be_empty) const;

  std::string path_;
  std::shared_ptr<Document> doc_;
  mutable std::map<std::string, std::string> used_;
  mutable std::map<std::string, KeyFacts> facts_;
};

}  // namespace granular
