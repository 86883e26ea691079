// The execution spaces every typed test runs on: all enabled host backends.
#pragma once
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>

namespace granular::testing {

using ExecSpaces = ::testing::Types<
#ifdef KOKKOS_ENABLE_OPENMP
    Kokkos::OpenMP
#if defined(KOKKOS_ENABLE_SERIAL) || defined(KOKKOS_ENABLE_CUDA)
    ,
#endif
#endif
#ifdef KOKKOS_ENABLE_SERIAL
    Kokkos::Serial
#ifdef KOKKOS_ENABLE_CUDA
    ,
#endif
#endif
#ifdef KOKKOS_ENABLE_CUDA
    Kokkos::Cuda
#endif
    >;

}  // namespace granular::testing
