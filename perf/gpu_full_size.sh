#!/usr/bin/env bash
# The frictional step at full size on one GPU: throughput and device memory per particle
# (array by array) at 1M, 4M and 16M spheres, then the largest tiling of the peer packing
# that fits the card (100M first), then the device test suite. docs/gpu_memory.md reads the
# results; perf/plot_gpu_full_size.py charts them.
#
#   perf/gpu_full_size.sh BIN_DIR PACKING_32768.data OUT_DIR [TEST_SECONDS]
#
# BIN_DIR holds the CUDA build's bench_dem_throughput (and granular_tests, run when present).
# GPU_ROWS picks the fixed rows (default "1m 4m 4m_frictionless 16m"); GPU_BIG_TILES the
# tilings tried in turn for the largest run (default 100.7M, 83.9M, 67.1M, 33.6M spheres).
set -u
bin=$1 data=$2 out=$3 test_seconds=${4:-180}
mkdir -p "$out"
say() { printf '[gpu_full_size %s] %s\n' "$(date +%T)" "$*"; }
command -v nvidia-smi >/dev/null &&
  nvidia-smi --query-gpu=name,memory.total,memory.used,clocks.max.sm,driver_version --format=csv |
  tee "$out/gpu.csv"

bench() {  # name, extra args...
  local name=$1
  shift
  say "bench $name: $*"
  "$bin/bench_dem_throughput" --data "$data" --out "$out/$name.json" "$@" 2>&1 |
    grep -v ' rep [0-9]*: ' | tee "$out/$name.log"
  return "${PIPESTATUS[0]}"
}

# 32768 x 32, x 128, x 512. The first row run also measures the triad and copy bandwidth.
triad=
for row in ${GPU_ROWS:-1m 4m 4m_frictionless 16m}; do
  case $row in
  1m) bench friction_1m --physics friction --tile 4,4,2 --reps 3 --steps 1000 --warmup 200 $triad ;;
  4m) bench friction_4m --physics friction --tile 4,4,8 --reps 3 --steps 500 --warmup 100 $triad ;;
  4m_frictionless)
    bench frictionless_4m --physics frictionless --tile 4,4,8 --reps 3 --steps 500 --warmup 100 $triad ;;
  16m) bench friction_16m --physics friction --tile 8,8,8 --reps 3 --steps 200 --warmup 50 $triad ;;
  *) say "unknown row $row" ;;
  esac
  triad=--no-triad
done

# The largest that fits, the first of the list that runs.
for t in ${GPU_BIG_TILES:-16,16,12 16,16,10 16,16,8 16,16,4}; do
  if bench "friction_${t//,/x}" --physics friction --tile "$t" --reps 1 --steps 200 --warmup 50 \
    --no-triad; then
    break
  fi
  say "tiling $t did not run (see above); trying a smaller one"
done

if [ -x "$bin/granular_tests" ]; then
  # The device copies of the typed tests (/0 is the Serial copy) and every other test but the
  # MPI ranks' and LAMMPS' (no mpirun or lmp there).
  say "device test suite (at most $test_seconds s)"
  timeout "$test_seconds" "$bin/granular_tests" --gtest_filter="-*/0.*:Mpi*:LammpsForces*" > "$out/tests.log" 2>&1
  echo "granular_tests exit $?" >> "$out/tests.log"
  grep -E '^\[  (PASSED|FAILED|SKIPPED) |^\[==========\]|exit' "$out/tests.log" | tail -n 40
  grep -c '^\[       OK \]' "$out/tests.log"
fi
say done
