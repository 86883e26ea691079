#!/usr/bin/env bash
# The main job: set everything up, then run the default scene (isotropic compression of
# 4096 spheres). Extra arguments go to `granular run` (e.g. --threads 2, --out DIR).
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# Only the engine and its Python package: the tests and benchmarks are the test command's
# (about nine minutes of a first build on two cores).
GRANULAR_TARGETS=${GRANULAR_TARGETS:-granular granular_python} "$repo/scripts/setup.sh"
scene=${GRANULAR_SCENE:-$repo/scenarios/packings/isotropic_compression.toml}
cd "$repo"
exec "${GRANULAR_BUILD:-$repo/build}/bin/granular" run "$scene" "$@"
