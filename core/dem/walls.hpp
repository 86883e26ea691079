// Planar rigid walls: scene objects with an outward normal (pointing away from the
// particles), a reference point on the plane and a prescribed motion (fixed, constant
// velocity, or a table of displacement along the normal against time). A wall is a
// contact partner of infinite mass and radius; its material is a species slot of the
// contact model's pair tables (so the same model structs evaluate sphere-wall pairs).
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "core/run/error.hpp"

namespace granular {

// What a kernel sees of one wall at the current time.
struct Wall {
  double n[3];   // outward unit normal: particles live on the side (x - p).n < 0
  double p[3];   // a point on the plane (moves with the wall)
  double v[3];   // wall velocity
  int material;  // species slot of the pair tables
};

enum class WallMotion { Fixed, Velocity, Table };

// A wall as a scene describes it (host side).
struct WallSpec {
  std::string name;
  double normal[3] = {0, 0, 1};
  double point[3] = {0, 0, 0};  // position at t = 0
  int material = 0;
  WallMotion motion = WallMotion::Fixed;
  double velocity[3] = {0, 0, 0};  // Velocity: constant
  // Table: displacement u(t) along the outward normal (negative = into the sample),
  // linear between the points, held at the end values outside them.
  std::vector<double> table_t, table_u;

  // Position and velocity of the plane's reference point at time t.
  void state(double t, double x[3], double v[3]) const {
    for (int d = 0; d < 3; ++d) x[d] = point[d], v[d] = 0.0;
    if (motion == WallMotion::Velocity) {
      for (int d = 0; d < 3; ++d) x[d] += velocity[d] * t, v[d] = velocity[d];
    } else if (motion == WallMotion::Table && !table_t.empty()) {
      double u = table_u.front(), du = 0.0;
      if (t >= table_t.back()) {
        u = table_u.back();
      } else if (t > table_t.front()) {
        size_t k = 1;
        while (table_t[k] < t) ++k;
        const double h = table_t[k] - table_t[k - 1];
        du = (table_u[k] - table_u[k - 1]) / h;
        u = table_u[k - 1] + du * (t - table_t[k - 1]);
      }
      for (int d = 0; d < 3; ++d) x[d] += u * normal[d], v[d] = du * normal[d];
    }
  }

  // Normalises the normal and checks the table; `where` names the scene key for messages.
  void validate(const std::string& where) {
    const double len =
        std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(len > 0) || !std::isfinite(len))
      throw InputError(where + ".normal must be a non-zero vector");
    for (double& c : normal) c /= len;
    if (motion == WallMotion::Table) {
      if (table_t.size() < 2 || table_t.size() != table_u.size())
        throw InputError(where + ": the motion table needs at least two (time, displacement)" +
                         " points and as many displacements as times");
      for (size_t k = 1; k < table_t.size(); ++k)
        if (!(table_t[k] > table_t[k - 1]))
          throw InputError(where + ": the motion table's times must increase");
    }
  }
};

// The walls of a system: host specifications and their current state in device memory.
template <class ExecSpace>
class WallSet {
 public:
  using view_type = Kokkos::View<Wall*, typename ExecSpace::memory_space>;

  WallSet() = default;
  explicit WallSet(std::vector<WallSpec> specs) : specs_(std::move(specs)) {
    walls_ = view_type("walls::state", specs_.size());
    host_ = Kokkos::create_mirror_view(walls_);
    update(0.0);
  }

  int size() const { return static_cast<int>(specs_.size()); }
  const std::vector<WallSpec>& specs() const { return specs_; }
  const view_type& view() const { return walls_; }
  const typename view_type::HostMirror& host() const { return host_; }

  // Moves every wall to its prescribed position at time t (one small copy per step).
  void update(double t) {
    if (specs_.empty()) return;
    for (int w = 0; w < size(); ++w) {
      const WallSpec& s = specs_[w];
      Wall& h = host_(w);
      for (int d = 0; d < 3; ++d) h.n[d] = s.normal[d];
      s.state(t, h.p, h.v);
      h.material = s.material;
    }
    Kokkos::deep_copy(walls_, host_);
  }

 private:
  std::vector<WallSpec> specs_;
  view_type walls_;
  typename view_type::HostMirror host_;
};

}  // namespace granular
