// Host-side vector code for x86-64 GNU builds: the target attributes that compile single
// functions for AVX while the rest of the build stays portable, and the run-time check that
// decides whether those functions may run. Users: the contact batch
// (kernels/cpu/contact_batch.hpp), the neighbour build's candidate sweep
// (kernels/cpu/neighbor_sweep.hpp) and the near stream (kernels/cpu/near_stream.hpp).
#pragma once
#include <cstring>

#if defined(__GNUC__) && !defined(__CUDACC__) && !defined(__clang__) && defined(__x86_64__)
#define GRANULAR_HOST_AVX 1
#define GRANULAR_AVX __attribute__((target("avx")))
#define GRANULAR_AVX_INLINE __attribute__((target("avx"), always_inline)) inline
#define GRANULAR_ALWAYS_INLINE __attribute__((always_inline)) inline
// AVX2 for the gathers of the near stream (kernels/cpu/near_stream.hpp).
#define GRANULAR_AVX2 __attribute__((target("avx2")))
#define GRANULAR_AVX2_INLINE __attribute__((target("avx2"), always_inline)) inline
#else
#define GRANULAR_HOST_AVX 0
#endif

namespace granular {

#if GRANULAR_HOST_AVX
// Four doubles in one AVX register (GCC vector extensions), a comparison's lane masks, and
// the plain loads and stores of four consecutive doubles.
namespace simd4 {
using V = double __attribute__((vector_size(32)));
using M = long __attribute__((vector_size(32)));
GRANULAR_AVX_INLINE V load(const double* a) {
  V v;
  std::memcpy(&v, a, sizeof v);
  return v;
}
GRANULAR_AVX_INLINE void store(double* a, V v) { std::memcpy(a, &v, sizeof v); }
GRANULAR_AVX_INLINE V splat(double x) { return V{x, x, x, x}; }
}  // namespace simd4
#endif

// Whether this processor (and its operating system) runs AVX instructions (false where no
// AVX code is compiled).
inline bool cpu_has_avx() {
#if GRANULAR_HOST_AVX
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx") != 0;
  }();
  return has;
#else
  return false;
#endif
}

// Whether this processor runs AVX2 instructions (false where no AVX code is compiled).
inline bool cpu_has_avx2() {
#if GRANULAR_HOST_AVX
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
#else
  return false;
#endif
}

}  // namespace granular
