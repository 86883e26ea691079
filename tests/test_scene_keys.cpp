// `granular keys`: the keys a driver reads, learned from its shipped scene files.
#include <gtest/gtest.h>
#include <toml++/toml.h>

#include <algorithm>

#include "scenarios/common/scene_keys.hpp"

using granular::InputError;
using granular::scene_keys;

namespace {
void leaves(const toml::table& t, const std::string& prefix, std::vector<std::string>& out) {
  for (const auto& [k, node] : t) {
    const std::string key =
        prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (const toml::table* sub = node.as_table())
      leaves(*sub, key, out);
    else
      out.push_back(key);
  }
}
}  // namespace

TEST(SceneKeys, ListsEveryKeyOfTheShippedFilesWithKindDefaultRulesAndMeaning) {
  const auto k = scene_keys("isotropic_compression");
  ASSERT_FALSE(k.files.empty());
  // Every key the shipped files hold is listed (nothing a user can set is left out).
  for (const std::string& path : k.files) {
    std::vector<std::string> present;
    leaves(toml::parse_file(path), "", present);
    for (const std::string& key : present)
      if (key != "scene") EXPECT_TRUE(k.keys.count(key)) << key << " of " << path;
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

TEST(SceneKeys, AnUnknownSceneIsRefusedListingTheKnownOnes) {
  try {
    scene_keys("isotropic_compresion");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("isotropic_compression"), std::string::npos) << e.what();
  }
}
