#!/usr/bin/env bash
# Wall-clock cost of each force model in the confined compression of 514 hydrogel balls
# (scenarios/soft/confined_compression_hydrogel.toml), against the times the source study reports
# for the same scene: 304 s (classical Hertz), 1030 s (MC-stress), 2715 s (MC-strain).
# Each repetition runs the whole scene (preparation, then one compression per model from
# the same settled packing); the scene times every model's compression on its own.
#
#   perf/soft_compression_speed.sh [--reps R] [--threads T] [--out FILE]
#
# Writes perf/results/soft_compression_<T>t.json: per model the wall seconds of every
# repetition, their median, the ratio source / engine, the ratio to the classical model, and
# the breakdown by pass (`granular run --kernel-times`: median seconds per kernel over the
# repetitions, and what no kernel accounts for, the sampling and the host's bookkeeping).
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
reps=3 threads=2 out=""
while [ $# -gt 0 ]; do
  case $1 in
    --reps) reps=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -h|--help) sed -n 2,12p "$0"; exit 0 ;;
    *) echo "unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
out=${out:-$repo/perf/results/soft_compression_${threads}t.json}
"$repo/scripts/setup.sh" >&2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for r in $(seq 1 "$reps"); do
  echo "[soft_compression] repetition $r of $reps" >&2
  OMP_PROC_BIND=spread OMP_PLACES=cores "$repo/build/bin/granular" run \
    "$repo/scenarios/soft/confined_compression_hydrogel.toml" --out "$work/rep$r" \
    --threads "$threads" --quiet --kernel-times >&2
done
/usr/bin/python3 - "$work" "$reps" "$threads" "$out" <<'PY'
import json, os, platform, statistics, sys
work, reps, threads, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
source = {"classical": 304.0, "mc_stress": 1030.0, "mc_strain": 2715.0}
runs = [json.load(open(os.path.join(work, f"rep{r}", "summary.json"))) for r in range(1, reps + 1)]
kernels = [json.load(open(os.path.join(work, f"rep{r}", "kernel_times.json"))) for r in range(1, reps + 1)]
def passes(label):
    """Median seconds per kernel of the model's compression over the repetitions."""
    per = {}
    for kt in kernels:
        region = next(g for g in kt["regions"] if g["name"] == "compression " + label)
        for k in region["kernels"]:
            per.setdefault(k["name"], []).append(k["seconds"])
        per.setdefault("(no kernel)", []).append(region["wall_seconds"] - region["kernel_seconds"])
    rows = {name: statistics.median(v) for name, v in per.items() if len(v) == len(kernels)}
    return dict(sorted(rows.items(), key=lambda kv: -kv[1]))
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
res = {"benchmark": "soft_compression", "scene": "scenarios/soft/confined_compression_hydrogel.toml",
       "threads": threads, "repetitions": reps, "cpu_model": cpu, "hardware_threads": os.cpu_count(),
       "python": platform.python_version(), "preparation_wall_seconds":
       [r["preparation"]["wall_seconds"] for r in runs], "models": {}}
lines = []
for label in runs[0]["models"]:
    walls = [r["models"][label]["wall_seconds"] for r in runs]
    med = statistics.median(walls)
    family = "classical" if label == "classical" else "_".join(label.split("_")[:2])
    row = {"wall_seconds": walls, "median_wall_seconds": med,
           "steps": runs[0]["models"][label]["steps"],
           "max_force_N": runs[0]["models"][label]["max_force"]}
    if family in source:
        row["source_wall_seconds"] = source[family]
        row["speedup_over_source"] = source[family] / med
    row["seconds_by_pass"] = passes(label)
    res["models"][label] = row
    lines.append(f"{label:22s} median {med:7.2f} s  source {source.get(family, float('nan')):6.0f} s"
                 f"  ratio {row.get('speedup_over_source', float('nan')):7.0f}x")
classical = res["models"].get("classical")
for label, row in res["models"].items():
    if classical:
        row["cost_over_classical"] = row["median_wall_seconds"] / classical["median_wall_seconds"]
    top = ", ".join(f"{k} {v:.2f}" for k, v in list(row["seconds_by_pass"].items())[:4])
    lines.append(f"  {label:20s} {row.get('cost_over_classical', float('nan')):5.2f}x classical; {top}")
tmp = out + ".tmp"
with open(tmp, "w") as f:
    json.dump(res, f, indent=2)
os.replace(tmp, out)
print("\n".join(lines))
print(f"written {out}")
PY
