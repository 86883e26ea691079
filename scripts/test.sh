#!/usr/bin/env bash
# The test command: set everything up, run the whole test suite (every test with 1 and 2
# threads), then check that the engine still compiles and links with Kokkos' CUDA backend
# when nvcc is available (skipped, and said so, when it is not).
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GRANULAR_BUILD:-$repo/build}
"$repo/scripts/setup.sh"
jobs=${GRANULAR_JOBS:-$(nproc 2>/dev/null || echo 2)}
(cd "$build" && ctest -j "$jobs" --output-on-failure)
GRANULAR_CUDA_CHECK=1 GRANULAR_SKIP_BUILD=1 "$repo/scripts/setup.sh"
