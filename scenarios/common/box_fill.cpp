// Random insertion into a region and settling (see box_fill.hpp). Host code, once per scene.
#include "scenarios/common/box_fill.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "core/run/error.hpp"
#include "core/run/rng.hpp"

namespace granular {

HostParticles fill_region(const FillSpec& s, const PeriodicBox& box) {
  if (s.count < 1) throw InputError("fill: the particle count must be positive");
  if (!(s.diameter_mean > 0) || s.diameter_spread < 0 || s.diameter_spread >= 1)
    throw InputError("fill: need diameter_mean > 0 and 0 <= diameter_spread < 1");
  const int n = s.count;
  HostParticles h;
  h.resize(n);
  double a_max = 0, vol = 0;
  for (int i = 0; i < n; ++i) {
    Stream st(s.seed, static_cast<std::uint64_t>(i));
    const double d = s.diameter_mean * st.uniform(1 - s.diameter_spread, 1 + s.diameter_spread);
    h.radius[i] = 0.5 * d, h.density[i] = s.density, h.species[i] = s.species;
    a_max = std::max(a_max, 0.5 * d);
    vol += M_PI / 6 * d * d * d;
  }
  double len[3], region = 1;
  for (int d = 0; d < 3; ++d) {
    len[d] = s.hi[d] - s.lo[d];
    region *= len[d];
    if (!(len[d] > (box.periodic[d] ? 0.0 : 2 * a_max)))
      throw InputError("fill: the insertion region is thinner than the largest diameter");
  }
  // Grid hash over the region, cells no smaller than the largest diameter.
  int nc[3];
  double cl[3];
  for (int d = 0; d < 3; ++d)
    nc[d] = std::max(1, static_cast<int>(len[d] / (2 * a_max))), cl[d] = len[d] / nc[d];
  std::vector<std::vector<int>> cells(static_cast<size_t>(nc[0]) * nc[1] * nc[2]);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return h.radius[a] > h.radius[b]; });
  for (int i : order) {
    Stream st(s.seed ^ 0x2545f4914f6cdd1dULL, static_cast<std::uint64_t>(i));
    const double a = h.radius[i];
    bool placed = false;
    for (int attempt = 0; attempt < 200000 && !placed; ++attempt) {
      double x[3];
      int c[3];
      for (int d = 0; d < 3; ++d) {
        const double margin = box.periodic[d] ? 0.0 : a;  // keep off the walls
        x[d] = st.uniform(s.lo[d] + margin, s.hi[d] - margin);
        c[d] = std::min(nc[d] - 1, static_cast<int>((x[d] - s.lo[d]) / cl[d]));
      }
      bool ok = true;
      for (int dz = -1; dz <= 1 && ok; ++dz)
        for (int dy = -1; dy <= 1 && ok; ++dy)
          for (int dx = -1; dx <= 1 && ok; ++dx) {
            const int o[3] = {dx, dy, dz};
            int cc[3];
            bool inside = true;
            for (int d = 0; d < 3; ++d) {
              cc[d] = c[d] + o[d];
              if (box.periodic[d])
                cc[d] = (cc[d] + nc[d]) % nc[d];
              else if (cc[d] < 0 || cc[d] >= nc[d])
                inside = false;
            }
            if (!inside) continue;
            for (int j : cells[(cc[2] * nc[1] + cc[1]) * nc[0] + cc[0]]) {
              const double rx = box.min_image(x[0] - h.x[j], 0);
              const double ry = box.min_image(x[1] - h.y[j], 1);
              const double rz = box.min_image(x[2] - h.z[j], 2);
              const double sum = a + h.radius[j];
              if (rx * rx + ry * ry + rz * rz < sum * sum) {
                ok = false;
                break;
              }
            }
          }
      if (!ok) continue;
      h.x[i] = x[0], h.y[i] = x[1], h.z[i] = x[2];
      cells[(c[2] * nc[1] + c[1]) * nc[0] + c[0]].push_back(i);
      placed = true;
    }
    if (!placed)
      throw InputError("fill: could not insert particle " + std::to_string(i) +
                       " without overlap (volume fraction " + std::to_string(vol / region) +
                       " in the insertion region): make the region taller or insert fewer");
  }
  return h;
}

long settle(const std::function<void(long)>& advance, const std::function<bool()>& done, long every,
            long max_steps, long min_steps) {
  for (long steps = 0; steps < max_steps; steps += every) {
    if (steps >= min_steps && done()) return steps;
    advance(every);
  }
  return done() ? max_steps : -1;
}

}  // namespace granular
