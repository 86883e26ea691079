// Plain host-side description of a packing (no Kokkos), used by generators, file readers
// and tests before the data moves into a Particles store.
#pragma once
#include <vector>

namespace granular {

// Plain host-side description of a packing, used by generators, readers and tests.
struct HostParticles {
  std::vector<double> x, y, z;     // positions
  std::vector<double> vx, vy, vz;  // velocities
  std::vector<double> wx, wy, wz;  // angular velocities
  std::vector<double> radius;
  std::vector<double> density;  // per particle, so mass = density * 4/3 pi a^3
  std::vector<int> species;
  int size() const { return static_cast<int>(radius.size()); }
  void resize(int n) {
    for (auto* v : {&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &radius, &density}) v->assign(n, 0.0);
    species.assign(n, 0);
  }
};

}  // namespace granular
