#!/usr/bin/env bash
# The test suite built with AddressSanitizer and UndefinedBehaviorSanitizer (the engine and
# the tests; Kokkos itself is not instrumented), then run with every test once per thread
# count. Any report fails the run. Build in $GRANULAR_ASAN_BUILD (default <repo>/build-asan).
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GRANULAR_ASAN_BUILD:-$repo/build-asan}
jobs=${GRANULAR_JOBS:-$(nproc 2>/dev/null || echo 2)}
GRANULAR_SKIP_BUILD=1 "$repo/scripts/setup.sh"   # packages and Kokkos only
cache=${GRANULAR_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/granular}
flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGRANULAR_PERF=OFF \
    -DKokkos_ROOT="$cache/kokkos-3.4.1-openmp-serial" -DCMAKE_CXX_FLAGS="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
fi
cmake --build "$build" -j "$jobs" --target granular_tests
# Leaks are not checked: the HDF5 and OpenMP runtimes keep allocations until exit.
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1
(cd "$build" && ctest --output-on-failure)
