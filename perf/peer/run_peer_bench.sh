#!/usr/bin/env bash
# Side-by-side DEM benchmark: this engine against LAMMPS on the same packing, the same
# contact law, time step, skin and number of steps. One command does everything:
#
#   perf/peer/run_peer_bench.sh                    # N = 4096 32768, 3 repetitions
#   perf/peer/run_peer_bench.sh --big              # also N = 262144 (a 2x2x2 replica of 32768)
#   perf/peer/run_peer_bench.sh --sizes "4096" --reps 5
#   perf/peer/run_peer_bench.sh --walls --sizes 32768 --physics hertz_tsuji \
#       --models "hertz_mass hertz_tsuji"           # the walled box (z faces closed by walls)
#
#   1. installs LAMMPS (Debian package lammps, MPI build), GNU time and matplotlib if missing;
#   2. builds the engine (scripts/setup.sh);
#   3. makes each packing once with LAMMPS (perf/peer/gen_packing.lmp, one rank, seed 12345;
#      N >= 262144 as a 2x2x2 replica of N/8, perf/peer/replicate.lmp, unless GEN_REPLICATE=0),
#      cached as perf/peer/data/packing_<N>.data: both codes read this file;
#   4. times, interleaved (repetition 1 of every configuration, then repetition 2, ...):
#        engine --physics friction and frictionless with 1 and 2 threads,
#        LAMMPS hooke_abs, hooke_mass, frictionless_abs, frictionless_mass (perf/peer/bench.lmp)
#        with 1 and 2 MPI ranks,
#      and the triad bandwidth with 1 and 2 threads; peak resident memory of every process
#      (GNU time, per MPI rank);
#   5. perf/peer/summarize.py writes perf/results/peer_<UTC time>.json, peer_latest.md and
#      peer_latest.png (medians, ratios engine/LAMMPS, physics cross-check, memory, scaling).
#
# Options: --sizes "N1 N2 ..."  --big  --reps R  --steps S (timed, 2000)  --warmup W (500)
#          --models "hooke_abs hooke_mass frictionless_abs frictionless_mass"
#          --physics "friction frictionless"  --threads "1 2"  --ranks "1 2"
#          --no-install  --no-build  --results DIR (default perf/results)
#          --walls        the walled box: each packing with its z faces closed by flat walls
#                         (perf/peer/walls.lmp cuts packing_walls_<N>.data from packing_<N>.data
#                         and relaxes it; LAMMPS fix wall/gran, the engine's --walls)
#          --nice LEVEL   run every timed process (both codes alike) at this nice level; a
#                         negative level (root) shields the timings from other work on a
#                         shared machine
# Environment: GEN_NP (ranks for making a packing, default 1; another count gives another,
# equally valid packing).
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
peer=$repo/perf/peer
sizes="4096 32768"
reps=3
steps=2000
warmup=500
models="hooke_abs hooke_mass frictionless_abs frictionless_mass"
physics="friction frictionless"
threads="1 2"
ranks="1 2"
install=1
build=1
results=$repo/perf/results
nice_level=0
walls=0
while [ $# -gt 0 ]; do
  case $1 in
    --sizes) sizes=$2; shift ;;
    --big) sizes="$sizes 262144" ;;
    --reps) reps=$2; shift ;;
    --steps) steps=$2; shift ;;
    --warmup) warmup=$2; shift ;;
    --models) models=$2; shift ;;
    --physics) physics=$2; shift ;;
    --threads) threads=$2; shift ;;
    --ranks) ranks=$2; shift ;;
    --no-install) install=0 ;;
    --no-build) build=0 ;;
    --results) results=$2; shift ;;
    --nice) nice_level=$2; shift ;;
    --walls) walls=1 ;;
    -h | --help) sed -n '2,30p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
  shift
done

say() { printf '[peer] %s\n' "$*" >&2; }
as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"
  elif command -v sudo >/dev/null 2>&1; then sudo "$@"
  else say "need root (or sudo) to run: $*"; exit 1; fi
}

# ---- 1. peer code and tools ------------------------------------------------------------
if [ "$install" = 1 ]; then
  missing=()
  for p in lammps time python3-matplotlib; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    say "installing Debian packages: ${missing[*]}"
    as_root apt-get update -q
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${missing[@]}"
  fi
fi
command -v lmp >/dev/null || { say "lmp not found (Debian package lammps)"; exit 1; }
[ -x /usr/bin/time ] || { say "/usr/bin/time not found (Debian package time)"; exit 1; }

# ---- 2. the engine -----------------------------------------------------------------------
if [ "$build" = 1 ]; then "$repo/scripts/setup.sh"; fi
bench=${GRANULAR_BUILD:-$repo/build}/bin/bench_dem_throughput
[ -x "$bench" ] || { say "missing $bench (run scripts/setup.sh)"; exit 1; }

# ---- 3. packings, made by LAMMPS, shared by both codes ----------------------------------
mkdir -p "$peer/data"
make_packing() {  # n
  local n=$1 f=$peer/data/packing_$1.data small
  [ -s "$f" ] && return 0
  small=$((n / 8))
  if [ "$n" -ge 262144 ] && [ "${GEN_REPLICATE:-1}" = 1 ]; then
    # Large sizes: a 2 x 2 x 2 replica of the packing eight times smaller (made if needed).
    make_packing "$small"
    say "making the packing N = $n as a 2x2x2 replica of N = $small (cached in $f)"
    (cd "$peer/data" && lmp -in "$peer/replicate.lmp" -var in "packing_$small.data" \
      -var out "packing_$n.data.tmp" -log "gen_$n.log" -echo none -screen none)
  else
    say "making the packing N = $n with LAMMPS (cached in $f)"
    gen_np=${GEN_NP:-1}
    launch=()
    [ "$gen_np" -gt 1 ] && launch=(mpirun --allow-run-as-root --bind-to core -np "$gen_np")
    (cd "$peer/data" && "${launch[@]}" lmp -in "$peer/gen_packing.lmp" -var N "$n" \
      -var out "packing_$n.data.tmp" -log "gen_$n.log" -echo none -screen none)
    grep PACKING_DONE "$peer/data/gen_$n.log" >&2 || true
  fi
  mv "$f.tmp" "$f"
}
for n in $sizes; do make_packing "$n"; done
# The walled box: particles crossing a z face removed, the rest relaxed against the walls.
make_walls_packing() {  # n
  local f=$peer/data/packing_walls_$1.data
  [ -s "$f" ] && return 0
  say "making the walled packing from N = $1 with LAMMPS (cached in $f)"
  (cd "$peer/data" && lmp -in "$peer/walls.lmp" -var in "packing_$1.data" \
    -var out "packing_walls_$1.data.tmp" -log "gen_walls_$1.log" -echo none -screen none)
  grep WALLS_DONE "$peer/data/gen_walls_$1.log" >&2 || true
  mv "$f.tmp" "$f"
}
packing=packing_ engine_walls=() lammps_walls=()
if [ "$walls" = 1 ]; then
  for n in $sizes; do make_walls_packing "$n"; done
  packing=packing_walls_ engine_walls=(--walls) lammps_walls=(-var walls z)
fi

# ---- 4. interleaved timing ---------------------------------------------------------------
stamp=$(date -u +%Y%m%dT%H%M%SZ)
logs=$peer/logs/$stamp
mkdir -p "$logs"
say "logs in $logs"
export OMP_PROC_BIND=spread OMP_PLACES=cores
mpirun_cmd=(mpirun --allow-run-as-root --bind-to core -np)
timefmt="PEER_RSS_KB %M PEER_WALL_S %e"
prio=(nice -n "$nice_level")
{
  echo "sizes=$sizes"; echo "reps=$reps"; echo "steps=$steps"; echo "warmup=$warmup"
  echo "models=$models"; echo "physics=$physics"; echo "threads=$threads"; echo "ranks=$ranks"; echo "nice=$nice_level"
  echo "lammps_version=$(dpkg-query -W -f='${Version}' lammps 2>/dev/null || echo unknown)"
  echo "mpirun_version=$(mpirun --version 2>/dev/null | head -n1)"
  echo "git_commit=$(git -C "$repo" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "walls=$([ "$walls" = 1 ] && echo z || echo none)"
  for n in $sizes; do echo "md5_$n=$(md5sum < "$peer/data/$packing$n.data" | cut -d' ' -f1)"; done
} > "$logs/settings.txt"

run_engine() {  # physics n threads rep
  local out=$logs/engine_$1_N$2_t$3_r$4
  OMP_NUM_THREADS=$3 "${prio[@]}" /usr/bin/time -f "$timefmt" "$bench" --kokkos-threads="$3" --no-triad \
    --data "$peer/data/$packing$2.data" "${engine_walls[@]}" --physics "$1" --reps 1 \
    --steps "$steps" --warmup "$warmup" --out "$out.json" > "$out.log" 2>&1 || say "FAILED: $out.log"
  say "$(date -u +%T) engine $1 N=$2 threads=$3 rep=$4: $(grep -m1 -o 'median [0-9.e+-]* M' "$out.log" || echo '?')"
}
run_lammps() {  # model n ranks rep
  local out=$logs/lammps_$1_N$2_np$3_r$4.log
  local args=(-in "$peer/bench.lmp" -var data "$peer/data/$packing$2.data" -var model "$1"
    -var nrun "$steps" -var nwarm "$warmup" "${lammps_walls[@]}" -log none -echo none)
  if [ "$3" = 1 ]; then
    OMP_NUM_THREADS=1 "${prio[@]}" /usr/bin/time -f "$timefmt" lmp "${args[@]}" > "$out" 2>&1 || say "FAILED: $out"
  else
    # Each rank appends its own line to a file of its own (two ranks printing to one stream
    # at exit could interleave their lines and lose a figure).
    rm -f "$out.rss"
    OMP_NUM_THREADS=1 "${prio[@]}" "${mpirun_cmd[@]}" "$3" /usr/bin/time -a -o "$out.rss" \
      -f "$timefmt" lmp "${args[@]}" > "$out" 2>&1 || say "FAILED: $out"
  fi
  say "$(date -u +%T) lammps $1 N=$2 ranks=$3 rep=$4: $(grep -A40 PEER_TIMED_BEGIN "$out" | grep -m1 -o 'Loop time of [0-9.e+-]*' || echo '?')"
}
run_triad() {  # threads rep
  local out=$logs/triad_t$1_r$2
  local first=${sizes%% *}
  OMP_NUM_THREADS=$1 "${prio[@]}" "$bench" --kokkos-threads="$1" --data "$peer/data/packing_$first.data" \
    --physics frictionless --reps 1 --steps 1 --warmup 0 --out "$out.json" > "$out.log" 2>&1 ||
    say "FAILED: $out.log"
}

for rep in $(seq 1 "$reps"); do
  for t in $threads; do run_triad "$t" "$rep"; done
  for n in $sizes; do
    for phys in $physics; do for t in $threads; do run_engine "$phys" "$n" "$t" "$rep"; done; done
    for m in $models; do for np in $ranks; do run_lammps "$m" "$n" "$np" "$rep"; done; done
  done
done

# ---- 5. results ----------------------------------------------------------------------------
/usr/bin/python3 "$peer/summarize.py" "$logs" --results "$results"
