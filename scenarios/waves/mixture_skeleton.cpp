#include "scenarios/waves/mixture_skeleton.hpp"

#include <cmath>
#include <limits>

namespace granular {

Skeleton measure_skeleton(const ContactNetwork& net, const std::vector<int>& species,
                          const std::vector<double>& position, const double len[3], int stiff) {
  const int n = static_cast<int>(species.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Skeleton s;
  double load[3] = {0, 0, 0};
  int stiff_count = 0;
  for (int i = 0; i < n; ++i) stiff_count += species[i] == stiff;
  const int soft_count = n - stiff_count;
  // Contact ends by type: stiff partners of stiff particles counted from both ends, etc.
  double ends_ss = 0, ends_s_soft = 0, ends_soft_s = 0, ends_soft_soft = 0;
  std::vector<std::vector<std::pair<int, int>>> links(n);  // stiff–stiff: (partner, contact)
  for (int c = 0; c < net.size(); ++c) {
    const int a = net.i[c], b = net.j[c];
    const int hard = (species[a] == stiff) + (species[b] == stiff);  // 2, 1 or 0
    const int type = 2 - hard;
    const double* l = &net.branch[3 * c];
    load[type] += net.normal_force[c] * std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    ++s.contacts[type];
    if (type == 0) {
      ends_ss += 2;
      links[a].push_back({b, c}), links[b].push_back({a, c});
    } else if (type == 1) {
      ends_s_soft += 1, ends_soft_s += 1;
    } else {
      ends_soft_soft += 2;
    }
  }
  const double total = load[0] + load[1] + load[2];
  for (int t = 0; t < 3; ++t) s.share[t] = total > 0 ? load[t] / total : nan;
  s.z_stiff_stiff = stiff_count > 0 ? ends_ss / stiff_count : nan;
  s.z_stiff_soft = stiff_count > 0 ? ends_s_soft / stiff_count : nan;
  s.z_soft_stiff = soft_count > 0 ? ends_soft_s / soft_count : nan;
  s.z_soft_soft = soft_count > 0 ? ends_soft_soft / soft_count : nan;

  // Clusters of the stiff–stiff network, each particle placed at an image of the box relative
  // to its cluster's first particle: a contact that closes a loop onto a different image wraps.
  std::vector<int> cluster(n, -1);
  std::vector<long> image(3 * static_cast<size_t>(n), 0);
  int largest = 0;
  for (int root = 0; root < n; ++root) {
    if (species[root] != stiff || cluster[root] >= 0) continue;
    int size = 0;
    bool wraps[3] = {false, false, false};
    std::vector<int> todo = {root};
    cluster[root] = root;
    while (!todo.empty()) {
      const int a = todo.back();
      todo.pop_back();
      ++size;
      for (const auto& [b, c] : links[a]) {
        // The branch vector runs from the lower identity to the higher one.
        const double sign = net.i[c] == a ? 1.0 : -1.0;
        long want[3];
        for (int d = 0; d < 3; ++d) {
          const double reach = position[3 * a + d] + sign * net.branch[3 * c + d];
          want[d] = image[3 * a + d] + std::lround((reach - position[3 * b + d]) / len[d]);
        }
        if (cluster[b] < 0) {
          cluster[b] = root;
          for (int d = 0; d < 3; ++d) image[3 * b + d] = want[d];
          todo.push_back(b);
        } else {
          for (int d = 0; d < 3; ++d) wraps[d] = wraps[d] || image[3 * b + d] != want[d];
        }
      }
    }
    if (size > largest) {
      largest = size;
      s.wrapping_axes = wraps[0] + wraps[1] + wraps[2];
    }
  }
  s.largest_cluster = stiff_count > 0 ? static_cast<double>(largest) / stiff_count : nan;
  return s;
}

}  // namespace granular
