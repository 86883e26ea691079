#!/usr/bin/env bash
# CUDA-enabled Kokkos 3.4.1 (Serial host + Cuda device, sm_80) in a cached prefix, so the
# engine can be compile-checked with the CUDA backend on machines that have nvcc but no GPU.
#
# Sourced by scripts/setup.sh after fetch_kokkos_source/build_kokkos are defined; it then
# uses $cache, $kokkos_src, $jobs, say and fetch_kokkos_source from there. Defines:
#   kokkos_cuda         the install prefix ($cache/kokkos-3.4.1-cuda-sm80)
#   build_kokkos_cuda   builds and installs it (no-op when already installed)
# Run standalone for testing:  bash scripts/kokkos_cuda.sh
#
# Downstream CMake projects (CUDA on PATH, or nvcc_wrapper cannot find nvcc):
#   cmake -DCMAKE_CXX_COMPILER=$kokkos_cuda/bin/nvcc_wrapper -DKokkos_ROOT=$kokkos_cuda ...
# With the default g++ instead, Kokkos' installed config redirects only the targets that
# link Kokkos::kokkos to nvcc_wrapper (via bin/kokkos_launch_compiler); both ways work.
#
# Kokkos 3.4.1 predates CUDA 13, so a copy of the source is patched (the cached source used
# by the host build stays untouched). There is no Hopper (sm_90) arch option in 3.4.1;
# the sm_80 code carries PTX, which the driver JIT-compiles on H100/H200 (edit 4 below
# lets Kokkos accept that instead of aborting at initialize).

# ---- fallbacks when run standalone (setup.sh defines all of these) -------------------
if [ -z "${cache:-}" ]; then
  cache=${GRANULAR_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/granular}
fi
: "${kokkos_version:=3.4.1}"
: "${kokkos_src:=$cache/src/kokkos-$kokkos_version}"
: "${jobs:=${GRANULAR_JOBS:-$(nproc 2>/dev/null || echo 2)}}"
declare -F say >/dev/null || say() { printf '[kokkos-cuda] %s\n' "$*" >&2; }
declare -F fetch_kokkos_source >/dev/null || fetch_kokkos_source() {
  [ -f "$kokkos_src/CMakeLists.txt" ] && return 0
  say "Kokkos source missing at $kokkos_src (run scripts/setup.sh first)"; return 1
}

kokkos_cuda=$cache/kokkos-$kokkos_version-cuda-sm80
kokkos_cuda_src=$cache/src/kokkos-$kokkos_version-cuda13

# nvcc_wrapper calls plain "nvcc"; the CUDA toolkit is not on PATH by default.
if [ -d /usr/local/cuda/bin ]; then
  case ":$PATH:" in *:/usr/local/cuda/bin:*) ;; *) PATH=/usr/local/cuda/bin:$PATH; export PATH ;; esac
fi

# Copy the cached source and adjust the copy for CUDA 13. Each edit is checked, so a
# source that does not look as expected fails loudly instead of building something odd.
prepare_kokkos_cuda_source() {
  fetch_kokkos_source || return 1
  local dst=$kokkos_cuda_src
  [ -f "$dst/.cuda13-patched" ] && return 0
  rm -rf "$dst"; cp -a "$kokkos_src" "$dst"

  # 1. nvcc_wrapper falls back to -arch=sm_35 whenever no -arch is given (also during
  #    CMake's compiler checks); CUDA 13 dropped everything below sm_75.
  sed -i 's/^default_arch="sm_35"$/default_arch="sm_80"/' "$dst/bin/nvcc_wrapper"
  grep -q '^default_arch="sm_80"$' "$dst/bin/nvcc_wrapper" ||
    { say "nvcc_wrapper: default_arch edit did not apply"; return 1; }

  # 2. Kokkos' half_t for CUDA does not compile against CUDA 13's cuda_fp16.h. Making the
  #    block's opening #if false leaves Kokkos_Half.hpp's fallback (half_t = float) in use.
  local half=$dst/core/src/Cuda/Kokkos_Cuda_Half.hpp
  sed -i 's/^#if !(defined(KOKKOS_COMPILER_CLANG) && KOKKOS_COMPILER_CLANG < 900) && \\$/#if 0 \&\& !(defined(KOKKOS_COMPILER_CLANG) \&\& KOKKOS_COMPILER_CLANG < 900) \&\& \\/' "$half"
  grep -q '^#if 0 && !(defined(KOKKOS_COMPILER_CLANG)' "$half" ||
    { say "Kokkos_Cuda_Half.hpp: disabling edit did not apply"; return 1; }

  # 3. CUDA 13 changed cudaMemPrefetchAsync(ptr, bytes, int device, stream) to
  #    (ptr, bytes, cudaMemLocation location, unsigned flags, stream).
  local space=$dst/core/src/Cuda/Kokkos_CudaSpace.cpp
  perl -0pi -e 's/cudaMemPrefetchAsync\(ptr, bytes, space\.cuda_device\(\),\s*space\.cuda_stream\(\)\)/cudaMemPrefetchAsync(ptr, bytes,\n        cudaMemLocation{cudaMemLocationTypeDevice, space.cuda_device()}, 0,\n        space.cuda_stream())/' "$space"
  grep -q 'cudaMemLocation{cudaMemLocationTypeDevice, space.cuda_device()}, 0' "$space" ||
    { say "Kokkos_CudaSpace.cpp: cudaMemPrefetchAsync edit did not apply"; return 1; }

  # 4. Not a CUDA 13 issue: Kokkos 3.4.1 aborts at start-up whenever the compiled major
  #    arch differs from the device's ("compute capability 8.0 on device with compute
  #    capability 9.0 is not supported"), although the sm_80 PTX in the binary is JIT-
  #    compiled and runs fine on H100/H200 (sm_90). Abort only when the binary targets a
  #    newer arch than the device; the warning Kokkos prints right after stays.
  local inst=$dst/core/src/Cuda/Kokkos_Cuda_Instance.cpp
  sed -i 's/^\( *\)if (compiled_major != cudaProp.major || compiled_minor > cudaProp.minor) {$/\1if (compiled_major > cudaProp.major ||\n\1    (compiled_major == cudaProp.major \&\& compiled_minor > cudaProp.minor)) {/' "$inst"
  grep -q '^ *if (compiled_major > cudaProp.major ||$' "$inst" ||
    { say "Kokkos_Cuda_Instance.cpp: arch check edit did not apply"; return 1; }

  touch "$dst/.cuda13-patched"
}

build_kokkos_cuda() {
  local prefix=$kokkos_cuda
  [ -f "$prefix/lib/cmake/Kokkos/KokkosConfig.cmake" ] && return 0
  command -v nvcc >/dev/null 2>&1 || { say "nvcc not found, cannot build CUDA Kokkos"; return 1; }
  prepare_kokkos_cuda_source || return 1
  local bdir=$prefix.build
  rm -rf "$bdir"
  say "building CUDA Kokkos $kokkos_version (sm_80) into $prefix"
  cmake -S "$kokkos_cuda_src" -B "$bdir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_STANDARD=17 \
    -DCMAKE_CXX_COMPILER="$kokkos_cuda_src/bin/nvcc_wrapper" \
    -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_INSTALL_LIBDIR=lib \
    -DKokkos_ENABLE_CUDA=ON -DKokkos_ENABLE_CUDA_LAMBDA=ON -DKokkos_ARCH_AMPERE80=ON \
    -DKokkos_ENABLE_SERIAL=ON >"$bdir.log" 2>&1 ||
    { say "CUDA Kokkos configure failed, see $bdir.log"; return 1; }
  cmake --build "$bdir" -j "$jobs" >>"$bdir.log" 2>&1 &&
    cmake --install "$bdir" >>"$bdir.log" 2>&1 ||
    { say "CUDA Kokkos build failed, see $bdir.log"; return 1; }
  rm -rf "$bdir"
}

# Standalone: build right away.
if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  set -euo pipefail
  build_kokkos_cuda
  say "CUDA Kokkos ready in $kokkos_cuda"
fi
