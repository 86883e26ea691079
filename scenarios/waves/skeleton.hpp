// The load-bearing skeleton of a wave column (docs/model_mixtures_and_waves.md): rattlers are
// the particles left with fewer than `threshold` contacts once the rattlers found so far are
// taken out, one round after another; the two walls count as contacts. A pulse's first
// arrival runs through the skeleton, so its speed sees the skeleton's mass, not the sample's.
#pragma once
#include <cmath>
#include <vector>

#include "scenarios/common/config_state.hpp"

namespace granular {

// Mass fraction of the rattlers of a column between a source wall at x = xs and a receiver
// wall at x = x_end (periodic along y and z where the box is). O(N^2) pairs: meant for the
// columns of a wave scene (hundreds to a few thousand particles).
inline double rattler_mass_fraction(const ConfigState& c, double xs, double x_end, int threshold) {
  const HostParticles& h = c.particles;
  const int n = h.size();
  std::vector<std::vector<int>> partners(n);
  std::vector<int> walls(n, 0);
  const double xyz_len[3] = {c.box.len[0], c.box.len[1], c.box.len[2]};
  for (int i = 0; i < n; ++i) {
    if (h.x[i] - h.radius[i] < xs) ++walls[i];
    if (h.x[i] + h.radius[i] > x_end) ++walls[i];
    for (int j = i + 1; j < n; ++j) {
      double d[3] = {h.x[j] - h.x[i], h.y[j] - h.y[i], h.z[j] - h.z[i]};
      for (int k = 0; k < 3; ++k)
        if (c.box.periodic[k]) d[k] -= xyz_len[k] * std::round(d[k] / xyz_len[k]);
      const double r = h.radius[i] + h.radius[j];
      if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r)
        partners[i].push_back(j), partners[j].push_back(i);
    }
  }
  std::vector<int> count(n);
  std::vector<char> rattler(n, 0);
  for (int i = 0; i < n; ++i) count[i] = static_cast<int>(partners[i].size()) + walls[i];
  for (bool changed = true; changed;) {
    changed = false;
    for (int i = 0; i < n; ++i)
      if (!rattler[i] && count[i] < threshold) {
        rattler[i] = 1, changed = true;
        for (int j : partners[i]) --count[j];
      }
  }
  double total = 0, out = 0;
  for (int i = 0; i < n; ++i) total += c.mass[i], out += rattler[i] ? c.mass[i] : 0.0;
  return total > 0 ? out / total : 0.0;
}

}  // namespace granular
