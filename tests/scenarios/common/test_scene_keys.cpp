// `granular keys`: the keys a driver reads, learned from its shipped scene files.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/io/scene_file.hpp"
#include "scenarios/common/scene_keys.hpp"

using granular::InputError;
using granular::scene_keys;
using granular::SceneFile;

namespace {
// Reads `key` of `file` as the kind `granular keys` lists for it, so that the file's
// own unknown-key check counts it as read.
void read_as(const SceneFile& file, const std::string& key, const std::string& kind) {
  if (kind == "number")
    file.real_or_infinite(key);
  else if (kind == "integer")
    file.integer(key);
  else if (kind == "string")
    file.text(key);
  else if (kind == "flag")
    file.flag(key);
  else if (kind == "numbers")
    file.reals(key);
  else if (kind == "strings")
    file.texts(key);
  else
    ADD_FAILURE() << key << " has no known kind: '" << kind << "'";
}
}  // namespace

TEST(SceneKeys, ListsEveryKeyOfTheShippedFilesWithKindDefaultRulesAndMeaning) {
  const auto k = scene_keys("isotropic_compression");
  ASSERT_FALSE(k.files.empty());
  // Every key the shipped files hold is listed (nothing a user can set is left out): read
  // each listed key as its listed kind, and the file's own check finds no key left unread.
  for (const std::string& path : k.files) {
    const SceneFile file = SceneFile::load(path);
    file.text("scene");
    for (const auto& [key, doc] : k.keys)
      if (file.has(key)) read_as(file, key, doc.kind);
    EXPECT_NO_THROW(file.reject_unknown_keys()) << path;
  }
  const auto& count = k.keys.at("particles.count");
  EXPECT_EQ(count.kind, "integer");
  EXPECT_TRUE(count.required);
  EXPECT_NE(std::find(count.rules.begin(), count.rules.end(), "must be at least 2"),
            count.rules.end());
  const auto& background = k.keys.at("damping.background");
  EXPECT_FALSE(background.required);
  EXPECT_EQ(background.default_value, "0");
  EXPECT_EQ(k.keys.at("particles.diameter_min").meaning, "w = d_max/d_min = 3, uniform, mean 2");
  EXPECT_EQ(k.keys.at("run.dt").kind, "number");
  // The JSON schema holds the same keys.
  const std::string json = k.json().dump();
  EXPECT_NE(json.find("\"particles.count\""), std::string::npos);
}

// A key that only a shared check names, and that this driver neither reads nor asks about
// (mixture_moduli draws its gas through check_gas, which names particles.initial_speed), is
// not required: it is listed as "default absent", while the keys the driver reads keep their
// own facts, and a table of keys ([materials]) stays required.
TEST(SceneKeys, KeyOnlyACheckNamesIsListedAsDefaultAbsentNotRequired) {
  const auto k = scene_keys("mixture_moduli");
  const auto& speed = k.keys.at("particles.initial_speed");
  EXPECT_TRUE(speed.kind.empty());
  EXPECT_FALSE(speed.required);
  EXPECT_EQ(speed.default_value, "absent");
  EXPECT_TRUE(k.keys.at("particles.count").required);
  EXPECT_EQ(k.keys.at("particles.count").kind, "integer");
  EXPECT_TRUE(k.keys.at("materials").required);
}

TEST(SceneKeys, AnUnknownSceneIsRefusedListingTheKnownOnes) {
  try {
    scene_keys("isotropic_compresion");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("isotropic_compression"), std::string::npos) << e.what();
  }
}
