// The unit of each numeric key a scene file gives, declared once for `granular keys` (its
// table and its JSON schema). The scenes work in mm, µs and µg, so a key's number is in mm,
// µs, `mm us-1`, N, MPa, mJ, `ug mm-3`, `N mm-1` ... (docs/data_formats.md, "Units of
// results.h5", spells them the same way, as H5MD does). A pure number is `1`; where the number
// is a multiple of a scale of the scene (particle diameters, crossing times, the chains' t_c)
// the unit is `1` and the note names the scale; `mixed` says the unit follows another key (the
// note says which).
#pragma once
#include <string>
#include <vector>

namespace granular {

struct KeyUnit {
  const char* scenes;   // comma-separated scene names; "" for every scene
  const char* pattern;  // the key; a `*` segment stands for a name the file chooses
  const char* unit;     // H5MD spelling: "mm us-1", "MPa", "1", or "mixed"
  const char* note;     // the scale or the key the unit follows; "" when the unit says all
};

// Every declared entry, in lookup order.
const std::vector<KeyUnit>& key_unit_table();

// The entries that declare the unit of `key` in scene `scene`: exactly one for every numeric
// key of a shipped scene file (the tests hold the table to that).
std::vector<const KeyUnit*> key_units_of(const std::string& scene, const std::string& key);

// Whether `unit` is spelled as declared units must be: "1", "mixed", or symbols of the
// engine's unit system with signed integer powers separated by single spaces.
bool well_formed_unit(const std::string& unit);

}  // namespace granular
