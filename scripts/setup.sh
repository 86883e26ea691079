#!/usr/bin/env bash
# One-stop setup: Debian packages (toolchain and libraries), Kokkos 3.4.1 built from
# Debian's trilinos source package into a cache outside the clone, then the project build.
# Every step is skipped when its result is already there, so calling it again is cheap.
#
# Environment:
#   GRANULAR_CACHE   where Kokkos is cached   (default ${XDG_CACHE_HOME:-$HOME/.cache}/granular)
#   GRANULAR_BUILD   project build directory  (default <repo>/build)
#   GRANULAR_JOBS    parallel build jobs      (default: number of cores)
#   GRANULAR_TARGETS build targets, space-separated (default: all; the run command builds
#                    only `granular`, so the first result does not wait for tests and benchmarks)
#   GRANULAR_CUDA_CHECK=1  also build the engine with the CUDA backend (compile and link
#                    only) in $GRANULAR_CUDA_BUILD (default <repo>/build-cuda) when nvcc exists
#   GRANULAR_CUDA_TARGETS  what that check builds (default: granular, the engine with every
#                    kernel and scene; "all" adds the tests and benchmarks, which the device
#                    suite builds on a GPU machine: on two cores they would add half an hour)
#   GRANULAR_MPI=0   leave OpenMPI out (installed by default: the test suite checks that an
#                    ensemble spread over MPI ranks gives the same files as one process)
#   GRANULAR_VIEWERS=1  also install Chromium and ParaView (about 1 GB), so that the tests
#                    that open report.html and the XDMF time series in them run instead of
#                    skipping
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cache=${GRANULAR_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/granular}
build=${GRANULAR_BUILD:-$repo/build}
jobs=${GRANULAR_JOBS:-$(nproc 2>/dev/null || echo 2)}
kokkos_version=3.4.1

say() { printf '[setup] %s\n' "$*" >&2; }

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"
  elif command -v sudo >/dev/null 2>&1; then sudo "$@"
  else say "need root (or sudo) to run: $*"; exit 1; fi
}

# ---- 1. Debian packages ------------------------------------------------------------
packages=(build-essential g++ cmake make pkg-config ca-certificates gnupg
  libeigen3-dev libhdf5-dev libfftw3-dev libtomlplusplus-dev libcli11-dev
  libgtest-dev libbenchmark-dev python3 python3-matplotlib python3-h5py python3-numpy
  python3-dev pybind11-dev python3-pytest
  lammps python3-mdanalysis)  # the clients the data-format tests read the engine's files with
if [ "${GRANULAR_MPI:-1}" != 0 ]; then
  packages+=(libopenmpi-dev openmpi-bin)
fi
if [ "${GRANULAR_VIEWERS:-0}" = 1 ]; then
  packages+=(chromium paraview python3-paraview)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  say "installing Debian packages: ${missing[*]}"
  as_root apt-get update -q
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# ---- 2. Kokkos source from Debian's trilinos source package -------------------------
# Only the source package carries Kokkos with its OpenMP backend; the binary package is
# Serial-only. The apt sources of this machine are reused with deb -> deb-src, in a
# private apt state so the system configuration is left untouched.
kokkos_src=$cache/src/kokkos-$kokkos_version
fetch_kokkos_source() {
  [ -f "$kokkos_src/CMakeLists.txt" ] && return 0
  local work=$cache/src/apt
  rm -rf "$work"; mkdir -p "$work/sources.list.d" "$work/lists/partial" "$work/dl"
  if [ -f /etc/apt/sources.list.d/debian.sources ]; then
    sed -E 's/^Types:.*/Types: deb-src/' /etc/apt/sources.list.d/debian.sources \
      > "$work/sources.list.d/debian.sources"
  fi
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] || continue
    sed -nE 's/^[[:space:]]*deb(-src)?[[:space:]]+/deb-src /p' "$f" \
      > "$work/sources.list.d/$(basename "$f" .list)-src.list"
  done
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] && [ "$(basename "$f")" != debian.sources ] || continue
    sed -E 's/^Types:.*/Types: deb-src/' "$f" > "$work/sources.list.d/$(basename "$f")"
  done
  local opts=(-o Dir::Etc::SourceList=/dev/null -o "Dir::Etc::SourceParts=$work/sources.list.d"
    -o "Dir::State::Lists=$work/lists" -o APT::Sandbox::User=root)
  say "fetching the trilinos source package (Kokkos $kokkos_version lives inside it)"
  as_root apt-get "${opts[@]}" update -q >/dev/null
  (cd "$work/dl" && as_root apt-get "${opts[@]}" source --download-only -q trilinos >/dev/null)
  local tarball
  tarball=$(ls "$work"/dl/trilinos_*.orig.tar.* | head -n1)
  mkdir -p "$work/x"
  tar -xf "$tarball" -C "$work/x" --wildcards '*/packages/kokkos/*'
  mkdir -p "$(dirname "$kokkos_src")"
  rm -rf "$kokkos_src"
  mv "$work"/x/*/packages/kokkos "$kokkos_src"
  rm -rf "$work"
}

# build_kokkos <prefix> <extra cmake args...>
build_kokkos() {
  local prefix=$1; shift
  [ -f "$prefix/lib/cmake/Kokkos/KokkosConfig.cmake" ] && return 0
  fetch_kokkos_source
  local bdir=$prefix.build
  rm -rf "$bdir"
  say "building Kokkos $kokkos_version into $prefix"
  cmake -S "$kokkos_src" -B "$bdir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_STANDARD=17 \
    -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_INSTALL_LIBDIR=lib "$@" >"$bdir.log" 2>&1 ||
    { say "Kokkos configure failed, see $bdir.log"; exit 1; }
  cmake --build "$bdir" -j "$jobs" >>"$bdir.log" 2>&1 &&
    cmake --install "$bdir" >>"$bdir.log" 2>&1 ||
    { say "Kokkos build failed, see $bdir.log"; exit 1; }
  rm -rf "$bdir"
}

# Position-independent, so that the Python module (a shared object) can link the engine.
kokkos_host=$cache/kokkos-$kokkos_version-openmp-serial-pic
build_kokkos "$kokkos_host" -DKokkos_ENABLE_OPENMP=ON -DKokkos_ENABLE_SERIAL=ON \
  -DCMAKE_POSITION_INDEPENDENT_CODE=ON

# ---- 3. The project ------------------------------------------------------------------
if [ "${GRANULAR_SKIP_BUILD:-0}" != 1 ]; then
  # A build folder configured against another Kokkos (an older cache layout) is reconfigured.
  if [ ! -f "$build/CMakeCache.txt" ] ||
    ! grep -q "^Kokkos_DIR:PATH=$kokkos_host/" "$build/CMakeCache.txt"; then
    say "configuring the project in $build"
    cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release -DKokkos_ROOT="$kokkos_host" \
      -DKokkos_DIR="$kokkos_host/lib/cmake/Kokkos" \
      -DGRANULAR_MPI="$([ "${GRANULAR_MPI:-1}" != 0 ] && echo ON || echo OFF)" >/dev/null
  fi
  targets=()
  for t in ${GRANULAR_TARGETS:-}; do targets+=(--target "$t"); done
  say "building the project${GRANULAR_TARGETS:+ ($GRANULAR_TARGETS)}"
  cmake --build "$build" -j "$jobs" "${targets[@]}"
fi

# ---- 4. CUDA compile check (optional) -------------------------------------------------
# Kokkos' CUDA backend built from the same source (scripts/kokkos_cuda.sh adjusts a copy
# for CUDA 13); the engine (every kernel, scene and the library API) must compile and link
# against it, and with GRANULAR_CUDA_TARGETS=all the tests and benchmarks too.
if [ "${GRANULAR_CUDA_CHECK:-0}" = 1 ]; then
  # shellcheck source=scripts/kokkos_cuda.sh
  . "$repo/scripts/kokkos_cuda.sh"
  if ! command -v nvcc >/dev/null 2>&1; then
    say "CUDA compile check SKIPPED: nvcc not found (looked on PATH and in /usr/local/cuda/bin)"
  else
    build_kokkos_cuda
    cuda_build=${GRANULAR_CUDA_BUILD:-$repo/build-cuda}
    if [ ! -f "$cuda_build/CMakeCache.txt" ]; then
      say "configuring the CUDA build in $cuda_build"
      # The host compiler stays g++: Kokkos' CMake config sends only the targets that link
      # Kokkos through nvcc_wrapper, so host-only code (TOML, HDF5 wrappers) never meets nvcc.
      cmake -S "$repo" -B "$cuda_build" -DCMAKE_BUILD_TYPE=Release -DKokkos_ROOT="$kokkos_cuda" \
        >/dev/null
    fi
    cuda_targets=${GRANULAR_CUDA_TARGETS:-granular}
    say "CUDA compile check: building $cuda_targets with the CUDA backend"
    if [ "$cuda_targets" = all ]; then
      cmake --build "$cuda_build" -j "$jobs"
    else
      # shellcheck disable=SC2086  # a space-separated list of targets
      cmake --build "$cuda_build" -j "$jobs" --target $cuda_targets
    fi
    say "CUDA compile check passed (compiled and linked; running needs a GPU)"
  fi
fi
