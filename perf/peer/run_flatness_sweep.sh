#!/usr/bin/env bash
# Cost per particle-step against N at the same work per particle: one packing tiled 1, 2, 4,
# ... 64 times (periodic replicas, perf/peer/replicate.lmp), so every size has the same
# neighbours, contacts and rebuilds per particle and differs only in how much memory a step
# sweeps. Times this engine and LAMMPS on each tiling, interleaved, and the machine's own
# triad bandwidth against the working set (perf/bench_memory_curve.cpp).
#
#   perf/peer/run_flatness_sweep.sh                       # base 4096, tilings 1..64, 3 reps
#   perf/peer/run_flatness_sweep.sh --factors "1 8 64" --reps 5 --no-lammps
#
# Options: --base N (a packing perf/peer/run_peer_bench.sh made, default 4096)
#          --factors "1 2 4 ..." (powers of two up to 512)  --reps R (3)
#          --budget PS (particle-steps per timed run, 1e8; steps = PS / N within 300..10000)
#          --warmup W (200)  --physics friction|frictionless  --model hooke_mass (LAMMPS)
#          --threads "1 2"  --ranks "1 2"  --no-lammps  --nice LEVEL  --results DIR
# Writes perf/results/flatness_<UTC time>.{json,md,png} (perf/peer/summarize_flatness.py).
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
peer=$repo/perf/peer
base=4096
factors="1 2 4 8 16 32 64"
reps=3
budget=100000000
warmup=200
physics=friction
model=hooke_mass
threads="1 2"
ranks="1 2"
lammps=1
nice_level=0
results=$repo/perf/results
while [ $# -gt 0 ]; do
  case $1 in
    --base) base=$2; shift ;;
    --factors) factors=$2; shift ;;
    --reps) reps=$2; shift ;;
    --budget) budget=$2; shift ;;
    --warmup) warmup=$2; shift ;;
    --physics) physics=$2; shift ;;
    --model) model=$2; shift ;;
    --threads) threads=$2; shift ;;
    --ranks) ranks=$2; shift ;;
    --no-lammps) lammps=0 ;;
    --nice) nice_level=$2; shift ;;
    --results) results=$2; shift ;;
    -h | --help) sed -n '2,17p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
  shift
done

say() { printf '[flatness] %s\n' "$*" >&2; }
for v in "base=$base" "reps=$reps" "budget=$budget" "warmup=$warmup"; do
  [[ ${v#*=} =~ ^[0-9]+$ ]] || { say "--${v%%=*} takes a whole number, not '${v#*=}'"; exit 2; }
done
bin=${GRANULAR_BUILD:-$repo/build}/bin
for b in bench_dem_throughput bench_memory_curve; do
  [ -x "$bin/$b" ] || { say "missing $bin/$b (run scripts/setup.sh)"; exit 1; }
done
src=$peer/data/packing_$base.data
[ -s "$src" ] || { say "missing $src (perf/peer/run_peer_bench.sh --sizes $base makes it)"; exit 1; }
[ "$lammps" = 0 ] || command -v lmp >/dev/null || { say "lmp not found (Debian package lammps)"; exit 1; }

# Replica counts along x, y, z for a power-of-two factor: the doublings go to x, y, z in turn.
dims() {
  local f=$1 r=(1 1 1) k=0
  while [ "$f" -gt 1 ]; do
    [ $((f % 2)) -eq 0 ] || { say "factor $1 is not a power of two"; exit 2; }
    r[$k]=$((r[k] * 2)); f=$((f / 2)); k=$(((k + 1) % 3))
  done
  echo "${r[0]} ${r[1]} ${r[2]}"
}
tile_file() {  # factor -> path of the tiled packing (made once, cached beside the packings)
  local f=$1
  if [ "$f" = 1 ]; then echo "$src"; return; fi
  local out=$peer/data/tile_${base}_x$f.data
  if [ ! -s "$out" ]; then
    command -v lmp >/dev/null || { say "lmp not found: cannot tile"; exit 1; }
    read -r rx ry rz <<< "$(dims "$f")"
    say "tiling N = $base $rx x $ry x $rz (cached in $out)"
    (cd "$peer/data" && lmp -in "$peer/replicate.lmp" -var in "packing_$base.data" \
      -var out "$out.tmp" -var rx "$rx" -var ry "$ry" -var rz "$rz" -log none -echo none \
      -screen none)
    mv "$out.tmp" "$out"
  fi
  echo "$out"
}

stamp=$(date -u +%Y%m%dT%H%M%SZ)
logs=$peer/logs/flatness_$stamp
mkdir -p "$logs"
say "logs in $logs"
export OMP_PROC_BIND=spread OMP_PLACES=cores
prio=(nice -n "$nice_level")
{
  echo "base=$base"; echo "factors=$factors"; echo "reps=$reps"; echo "budget=$budget"
  echo "warmup=$warmup"; echo "physics=$physics"; echo "model=$model"; echo "threads=$threads"
  echo "ranks=$ranks"; echo "lammps=$lammps"; echo "nice=$nice_level"
  echo "lammps_version=$(dpkg-query -W -f='${Version}' lammps 2>/dev/null || echo unknown)"
  echo "git_commit=$(git -C "$repo" rev-parse --short HEAD 2>/dev/null || echo unknown)"
} > "$logs/settings.txt"

steps_for() {  # N -> timed steps
  local s=$(($1 > 0 ? budget / $1 : 300))
  [ "$s" -lt 300 ] && s=300
  [ "$s" -gt 10000 ] && s=10000
  echo "$s"
}
for f in $factors; do tile_file "$f" > /dev/null; done

for rep in $(seq 1 "$reps"); do
  for t in $threads; do
    OMP_NUM_THREADS=$t "${prio[@]}" "$bin/bench_memory_curve" --kokkos-threads="$t" \
      --out "$logs/memory_t${t}_r$rep.json" > "$logs/memory_t${t}_r$rep.log" 2>&1 ||
      say "FAILED: $logs/memory_t${t}_r$rep.log"
  done
  for f in $factors; do
    data=$(tile_file "$f")
    n=$((base * f))
    steps=$(steps_for "$n")
    for t in $threads; do
      out=$logs/engine_x${f}_t${t}_r$rep
      OMP_NUM_THREADS=$t "${prio[@]}" "$bin/bench_dem_throughput" --kokkos-threads="$t" --no-triad \
        --data "$data" --physics "$physics" --reps 1 --steps "$steps" --warmup "$warmup" \
        --out "$out.json" > "$out.log" 2>&1 || say "FAILED: $out.log"
      say "$(date -u +%T) engine N=$n threads=$t rep=$rep: $(grep -m1 -o 'median [0-9.e+-]* M' "$out.log" || echo '?')"
    done
    [ "$lammps" = 1 ] || continue
    for np in $ranks; do
      out=$logs/lammps_x${f}_np${np}_r$rep.log
      args=(-in "$peer/bench.lmp" -var data "$data" -var model "$model" -var nrun "$steps"
        -var nwarm "$warmup" -log none -echo none)
      if [ "$np" = 1 ]; then
        OMP_NUM_THREADS=1 "${prio[@]}" lmp "${args[@]}" > "$out" 2>&1 || say "FAILED: $out"
      else
        OMP_NUM_THREADS=1 "${prio[@]}" mpirun --allow-run-as-root --bind-to core -np "$np" \
          lmp "${args[@]}" > "$out" 2>&1 || say "FAILED: $out"
      fi
      say "$(date -u +%T) lammps N=$n ranks=$np rep=$rep: $(grep -A40 PEER_TIMED_BEGIN "$out" | grep -m1 -o 'Loop time of [0-9.e+-]*' || echo '?')"
    done
  done
done

/usr/bin/python3 "$peer/summarize_flatness.py" "$logs" --results "$results"
