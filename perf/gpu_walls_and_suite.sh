#!/usr/bin/env bash
# On a GPU machine, from the repository's root, with an unpacked perf/gpu_pack_build.sh
# archive in PACK_DIR: the walls' device tests (under cuda-gdb with a backtrace if they end the
# process), the device test suite through perf/gpu_suite_runner.py (it goes on after a test
# that ends the process), and a 4M-sphere frictional throughput row with its device memory.
#
#   perf/gpu_walls_and_suite.sh PACK_DIR OUT_DIR [SUITE_SECONDS]
set -u
pack=$1 out=$2 suite_seconds=${3:-230}
mkdir -p "$out"
export LD_LIBRARY_PATH=$pack/lib CUDA_CACHE_MAXSIZE=4294967296
t0=$(date +%s)
say() { echo "[$(($(date +%s) - t0)) s] $*"; }
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv | tee "$out/gpu.csv"
say walls
timeout 120 "$pack/bin/granular_tests" --gtest_filter='WallTest/*' >"$out/walls.log" 2>&1
echo "walls exit $?" >>"$out/walls.log"
grep -E '^\[  (PASSED|FAILED)|exit' "$out/walls.log"
if ! grep -q 'walls exit 0' "$out/walls.log"; then
  say "walls under cuda-gdb"
  timeout 90 cuda-gdb -batch -ex run -ex bt --args "$pack/bin/granular_tests" \
    --gtest_filter='WallTest/1.*' >"$out/walls_gdb.log" 2>&1
  tail -30 "$out/walls_gdb.log"
fi
say suite
PYTHONUNBUFFERED=1 python3 perf/gpu_suite_runner.py "$pack/bin/granular_tests" \
  '-*/0.*:Mpi*:LammpsForces*' "$out/tests.log" "$suite_seconds"
say bench
"$pack/bin/bench_dem_throughput" --data "$pack/data/packing_32768.data" \
  --out "$out/friction_4m.json" --physics friction --tile 4,4,8 --reps 3 --steps 500 \
  --warmup 100 2>&1 | grep -v ' rep [0-9]*: ' | tail -25
say done
