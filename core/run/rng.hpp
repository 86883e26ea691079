// Counter-based random streams: every stream is a pure function of (seed, index), so a
// particle's or a realization's numbers never depend on thread count or batching.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <cstdint>

namespace granular {

KOKKOS_INLINE_FUNCTION std::uint64_t splitmix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

class Stream {
 public:
  KOKKOS_INLINE_FUNCTION Stream(std::uint64_t seed, std::uint64_t index)
      : state_(splitmix64(seed ^ splitmix64(index + 0x632be59bd9b4e019ULL))) {}

  KOKKOS_INLINE_FUNCTION std::uint64_t next_u64() {
    state_ += 0x9e3779b97f4a7c15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1) with 53 random bits.
  KOKKOS_INLINE_FUNCTION double uniform() { return (next_u64() >> 11) * 0x1.0p-53; }
  KOKKOS_INLINE_FUNCTION double uniform(double a, double b) { return a + (b - a) * uniform(); }
  // Standard normal by Box-Muller (the second value is dropped to keep the stream simple).
  KOKKOS_INLINE_FUNCTION double normal() {
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    return Kokkos::Experimental::sqrt(-2.0 * Kokkos::Experimental::log(u1)) *
           Kokkos::Experimental::cos(2.0 * M_PI * u2);
  }

 private:
  std::uint64_t state_;
};

}  // namespace granular
