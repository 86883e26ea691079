// The few operations in which one lane of doubles differs from four: the contact laws are
// written once over a number type T with its mask type, and compiled for `double` (the scalar
// host loops and the device: masks are bool, a selection is a branch) and for four AVX lanes
// (the host's contact batch and near stream, kernels/cpu/: masks are lane masks, both outcomes
// are formed and selected). Every lane performs the scalar operations in the scalar order, so
// the two compilations give the same bits (tests/kernels/cpu/test_contact_batch.cpp).
//
//   lane_select(m, a, b)   a where m holds, else b
//   lane_any(m), lane_all(m)   whether any / every lane holds (the mask itself for bool): a
//                          rare branch is taken only where a lane needs it, so the scalar
//                          code keeps its branches
//   lane_not(m)            the negated mask
//   lane_sqrt(x)           the correctly rounded square root of each lane
//   Lane<T>::splat(c)      the constant c in every lane
#pragma once
#include <Kokkos_Core.hpp>

#include "kernels/cpu/host_simd.hpp"

namespace granular {

template <class T>
struct Lane {
  using mask = bool;
  KOKKOS_FORCEINLINE_FUNCTION static T splat(double c) { return c; }
};

KOKKOS_FORCEINLINE_FUNCTION double lane_select(bool m, double a, double b) { return m ? a : b; }
KOKKOS_FORCEINLINE_FUNCTION bool lane_any(bool m) { return m; }
KOKKOS_FORCEINLINE_FUNCTION bool lane_all(bool m) { return m; }
KOKKOS_FORCEINLINE_FUNCTION bool lane_not(bool m) { return !m; }
KOKKOS_FORCEINLINE_FUNCTION double lane_sqrt(double x) { return Kokkos::Experimental::sqrt(x); }

#if GRANULAR_HOST_AVX
template <>
struct Lane<simd4::V> {
  using mask = simd4::M;
  GRANULAR_AVX_INLINE static simd4::V splat(double c) { return simd4::splat(c); }
};
GRANULAR_AVX_INLINE simd4::V lane_select(simd4::M m, simd4::V a, simd4::V b) { return m ? a : b; }
GRANULAR_AVX_INLINE int lane_bits(simd4::M m) { return __builtin_ia32_movmskpd256((simd4::V)m); }
GRANULAR_AVX_INLINE bool lane_any(simd4::M m) { return lane_bits(m) != 0; }
GRANULAR_AVX_INLINE bool lane_all(simd4::M m) { return lane_bits(m) == 0xf; }
GRANULAR_AVX_INLINE simd4::M lane_not(simd4::M m) { return ~m; }
GRANULAR_AVX_INLINE simd4::V lane_sqrt(simd4::V x) { return __builtin_ia32_sqrtpd256(x); }
#endif

}  // namespace granular
