// Positions as 32-bit fixed-point fractions of the box: the mixed-precision force pass
// (DemParams::mixed_precision, docs/mixed_precision.md). Each coordinate becomes
// q = round((x - lo) / len * 2^32) modulo 2^32, 12 bytes per particle instead of 24, and the
// separation of two particles is the difference of their integers read as a signed 32-bit
// number times len / 2^32: the integer wrap-around is the minimum image of a periodic box, and
// the resolution is the same everywhere in the box (len / 2^32: 1.5e-8 mm in the benchmarks'
// 65 mm box of 32768 spheres of 1-3 mm). The positions the integrator advances stay in double; only the
// force pass reads the integers, and its forces are computed and summed in double.
#pragma once
#include <Kokkos_Core.hpp>
#include <cstdint>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"

namespace granular {

constexpr double kFixedPointSteps = 4294967296.0;  // 2^32 integer steps per box length

// The integer of coordinate x in a box dimension starting at lo, `per_length` = 2^32 / len:
// x rounded to the nearest step, taken modulo 2^32 (so positions outside the box, in a walled
// dimension or before a wrap, keep their separations).
KOKKOS_INLINE_FUNCTION std::uint32_t to_fixed_point(double x, double lo, double per_length) {
  const double s = (x - lo) * per_length + 0.5;
  long long t = static_cast<long long>(s);    // truncation toward zero ...
  t -= (s < static_cast<double>(t)) ? 1 : 0;  // ... made floor: round to nearest
  return static_cast<std::uint32_t>(static_cast<unsigned long long>(t));
}

// Separation qi - qj in length units: the unsigned difference (modulo 2^32) read as signed.
KOKKOS_FORCEINLINE_FUNCTION double fixed_point_separation(std::uint32_t qi, std::uint32_t qj,
                                                          double step) {
  return static_cast<double>(static_cast<std::int32_t>(qi - qj)) * step;
}

// The particles' fixed-point positions, refreshed from the double ones before every force pass
// of a mixed-precision system.
template <class ExecSpace>
struct FixedPositions {
  using view = Kokkos::View<std::uint32_t* [3], typename ExecSpace::memory_space>;
  view q;
  double step[3] = {0, 0, 0};  // length of one integer step per dimension: len / 2^32

  FixedPositions() = default;
  explicit FixedPositions(int n) : q("particles::x_fixed", n) {}
  bool allocated() const { return q.extent(0) > 0; }

  // q from p.x in the box as it is now (a strained box changes len, hence the steps).
  void update(const Particles<ExecSpace>& p, const PeriodicBox& box) {
    if (static_cast<int>(q.extent(0)) != p.n) q = view("particles::x_fixed", p.n);
    double lo[3], per[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = box.lo[d], per[d] = kFixedPointSteps / box.len[d];
      step[d] = box.len[d] / kFixedPointSteps;
    }
    auto x = p.x;
    auto out = q;
    Kokkos::parallel_for(
        "dem::fixed_point::update", Kokkos::RangePolicy<ExecSpace>(0, p.n),
        KOKKOS_LAMBDA(const int i) {
          out(i, 0) = to_fixed_point(x(i, 0), lo[0], per[0]);
          out(i, 1) = to_fixed_point(x(i, 1), lo[1], per[1]);
          out(i, 2) = to_fixed_point(x(i, 2), lo[2], per[2]);
        });
  }
};

}  // namespace granular
