// The declared units of the scene keys (scenarios/common/key_units.hpp): one for every numeric
// key of every shipped scene file, none that names no such key, each spelled as a unit.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "scenarios/common/key_units.hpp"
#include "scenarios/common/scene_keys.hpp"
#include "scenarios/scene_registry.hpp"

using granular::key_unit_table;
using granular::key_units_of;
using granular::KeyUnit;
using granular::scene_keys;
using granular::SceneKeys;
using granular::well_formed_unit;

namespace {

bool numeric(const std::string& kind) {
  return kind == "number" || kind == "numbers" || kind == "integer";
}

// The keys of every registered scene, learned once from the shipped files (a few seconds).
const std::map<std::string, SceneKeys>& every_scene() {
  static const std::map<std::string, SceneKeys> all = [] {
    std::map<std::string, SceneKeys> m;
    for (const granular::SceneEntry& e : granular::scene_registry()) m[e.name] = scene_keys(e.name);
    return m;
  }();
  return all;
}

}  // namespace

TEST(KeyUnits, EveryNumericKeyOfEveryShippedSceneHasExactlyOneDeclaredUnit) {
  size_t checked = 0;
  for (const auto& [scene, keys] : every_scene())
    for (const auto& [key, doc] : keys.keys) {
      const auto units = key_units_of(scene, key);
      if (numeric(doc.kind)) {
        ++checked;
        EXPECT_EQ(units.size(), 1u)
            << scene << ": " << key << " has " << units.size() << " declared units";
        EXPECT_FALSE(doc.unit.empty()) << scene << ": " << key;
      } else if (doc.kind.empty()) {
        // Only asked about here (a sweep replaces it, a wall target has none): where it has a
        // unit, one only.
        EXPECT_LE(units.size(), 1u) << scene << ": " << key;
      } else {
        EXPECT_TRUE(units.empty())
            << scene << ": " << key << " is a " << doc.kind << ", yet has a unit";
      }
    }
  EXPECT_GT(checked, 400u);  // the shipped scenes have about 470 numeric keys
}

TEST(KeyUnits, EveryDeclaredEntryNamesAKeyOfAShippedSceneAndIsSpelledAsAUnit) {
  std::set<const KeyUnit*> used;
  for (const auto& [scene, keys] : every_scene())
    for (const auto& [key, doc] : keys.keys)
      for (const KeyUnit* u : key_units_of(scene, key)) used.insert(u);
  for (const KeyUnit& u : key_unit_table()) {
    EXPECT_TRUE(used.count(&u)) << u.pattern << " (" << u.scenes
                                << ") names no key of a shipped scene: misspelt or stale";
    EXPECT_TRUE(well_formed_unit(u.unit)) << u.pattern << ": '" << u.unit << "'";
    if (std::string(u.unit) == "mixed") {
      EXPECT_STRNE(u.note, "") << u.pattern << ": a mixed unit must say what it follows";
    }
    for (const char* s = u.scenes; *s; ++s)
      EXPECT_NE(*s, ' ') << u.pattern << ": scene list '" << u.scenes << "' has a space";
  }
}

TEST(KeyUnits, UnitSpellingAcceptsH5mdFormsAndRefusesOthers) {
  for (const char* ok : {"1", "mixed", "mm", "mm us-1", "ug mm-3", "N mm-1", "mm us-2",
                         "ug mm-1 us-1", "MPa+2 us+2", "rad us-1", "deg", "us-1"})
    EXPECT_TRUE(well_formed_unit(ok)) << ok;
  for (const char* bad :
       {"", "mm/us", "mm  us-1", "mm us^-1", "km", "mm us-0", "mm mm-1", " mm", "kg/m^3", "MPa+"})
    EXPECT_FALSE(well_formed_unit(bad)) << bad;
}

// The units the scenes' own comments state: a declared unit that contradicts them would fail.
TEST(KeyUnits, DeclaredUnitsAgreeWithTheShippedFilesComments) {
  const auto unit = [](const std::string& scene, const std::string& key) {
    return every_scene().at(scene).keys.at(key).unit;
  };
  // two_particle_linear.toml: kn = 1e5 "(1e8 N/m)", gamma_n = 1000 "(1 kg/s)", speeds in mm/us.
  EXPECT_EQ(unit("two_particle_linear", "contact.kn"), "N mm-1");
  EXPECT_EQ(unit("two_particle_linear", "contact.gamma_n"), "ug us-1");
  EXPECT_EQ(unit("two_particle_linear", "collisions.impact_speeds"), "mm us-1");
  EXPECT_EQ(unit("two_particle_linear", "particles.density"), "ug mm-3");
  // confined_compression.toml: hydrogel E = 0.0233 "23.3 kPa"; wall speed 1e-4 "0.1 m/s";
  // gravity 9.81e-9 (9.81 m/s^2 in mm/us^2); the measured force in N.
  EXPECT_EQ(unit("confined_compression", "materials.hydrogel.young_modulus"), "MPa");
  EXPECT_EQ(unit("confined_compression", "compression.wall_speed"), "mm us-1");
  EXPECT_EQ(unit("confined_compression", "fill.gravity"), "mm us-2");
  EXPECT_EQ(unit("confined_compression", "compression.experiment_max_force"), "N");
  // soft_collision.toml: duration 6000 "6 ms".
  EXPECT_EQ(unit("soft_collision", "soft.duration"), "us");
  // mixture_moduli.toml: tangential stiffness "N/mm", viscosity "ug/(mm us)", pressures MPa.
  EXPECT_EQ(unit("mixture_moduli", "materials.glass.tangential_stiffness"), "N mm-1");
  EXPECT_EQ(unit("mixture_moduli", "materials.glass.viscosity"), "ug mm-1 us-1");
  EXPECT_EQ(unit("mixture_moduli", "preparation.pressures"), "MPa");
  // The chains are in reduced units: a pure number with its scale.
  EXPECT_EQ(unit("chain_impulse", "time.dt"), "1");
  EXPECT_NE(every_scene().at("chain_impulse").keys.at("time.dt").unit_note.find("t_c"),
            std::string::npos);
  // A key that is no number has no unit.
  EXPECT_TRUE(every_scene().at("elastic_moduli").keys.at("contact.normal").unit.empty());
}
