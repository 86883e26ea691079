// The particles a mixture study starts from (see mixture_gas.hpp).
#include "scenarios/waves/mixture_gas.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/run/rng.hpp"
#include "scenarios/common/packing_file.hpp"

namespace granular {

HostParticles mixture_gas(const GasSpec& gas, const MixtureMaterials& mats, int stiff, int soft,
                          double soft_fraction, PeriodicBox& box) {
  HostParticles h = random_gas(gas, box);
  const int n = h.size();
  std::vector<std::pair<double, int>> order(n);
  for (int i = 0; i < n; ++i) order[i] = {Stream(gas.seed + 7919, i).uniform(), i};
  std::sort(order.begin(), order.end());
  const int n_soft = static_cast<int>(std::round(soft_fraction * n));
  for (int k = 0; k < n; ++k) {
    const int i = order[k].second;
    h.species[i] = k < n_soft ? soft : stiff;
    h.density[i] = mats.materials[h.species[i]].density;
  }
  return h;
}

HostParticles mixture_from_file(const SceneFile& s, const MixtureMaterials& mats, int stiff,
                                int soft, PeriodicBox& box) {
  const std::string path = s.input_path("particles.from");
  const std::string group = s.text("particles.from_group", "/final_state");
  const std::vector<std::string> names = s.texts("particles.from_materials");
  s.require(!names.empty(), "particles.from_materials",
            "needs the material of each species of the packing file (species 0 first)");
  std::vector<int> slot;
  for (const std::string& name : names) {
    const int k = mats.slot(s, "particles.from_materials", name);
    s.require(k == stiff || k == soft, "particles.from_materials",
              "names \"" + name +
                  "\", which is neither mixture.stiff_material nor mixture.soft_material");
    slot.push_back(k);
  }
  // The materials give the densities: 1 stands in for the density H5MD and state groups lack.
  HostParticles h = read_scene_packing(s, "particles.from", path, 1.0, group, box);
  s.require(h.size() >= 16, "particles.from", "holds fewer than 16 particles");
  for (int i = 0; i < h.size(); ++i) {
    const int sp = h.species[i];
    s.require(sp >= 0 && sp < static_cast<int>(slot.size()), "particles.from_materials",
              "names " + std::to_string(slot.size()) + " material(s), but particle " +
                  std::to_string(i) + " of " + path + " is of species " + std::to_string(sp));
    s.require(h.radius[i] > 0 && std::isfinite(h.radius[i]), "particles.from",
              "particle " + std::to_string(i) + " has no positive radius");
    h.species[i] = slot[sp];
    h.density[i] = mats.materials[slot[sp]].density;
  }
  return h;
}

double soft_volume_fraction(const HostParticles& h, int soft) {
  double v_soft = 0, v = 0;
  for (int i = 0; i < h.size(); ++i) {
    const double r3 = h.radius[i] * h.radius[i] * h.radius[i];
    v += r3;
    if (h.species[i] == soft) v_soft += r3;
  }
  return v_soft / v;
}

}  // namespace granular
