#!/usr/bin/env bash
# The test command: set everything up, run the whole test suite (every test with 1 and 2
# threads), then check that the engine still compiles and links with Kokkos' CUDA backend
# when nvcc is available (skipped, and said so, when it is not).
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GRANULAR_BUILD:-$repo/build}
"$repo/scripts/setup.sh"
# One test process at a time: each already uses the cores (its 2-thread variant would
# otherwise compete with another test for them, and spinning threads slow both down).
# The `verify` label (the quick variants' references, about 20 minutes) and the `long` label
# (full scenes, tens of minutes each) are left out here: run them with `ctest -L verify` or
# `ctest -L long` in the build folder.
(cd "$build" && ctest --output-on-failure -LE 'verify|long')
GRANULAR_CUDA_CHECK=1 GRANULAR_SKIP_BUILD=1 "$repo/scripts/setup.sh"
