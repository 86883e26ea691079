#!/usr/bin/python3
"""Summarise one run of perf/peer/run_flatness_sweep.sh.

    summarize_flatness.py perf/peer/logs/flatness_<stamp> [--results perf/results]

Writes <results>/flatness_<stamp>.json (every repetition, medians), flatness_<stamp>.md (the
table) and flatness_<stamp>.png (throughput per particle against N relative to the smallest
tiling, both codes; the triad bandwidth against the working set, with the engine's resident
memory at each N marked). Throughput: particle-steps per second of the timed window, the
engine's own timer, LAMMPS' "Loop time". Every file is written whole or not at all.
"""
import argparse
import glob
import json
import math
import os
import re
import statistics

from peer_logs import read_settings

ap = argparse.ArgumentParser()
ap.add_argument("logs")
ap.add_argument("--results", default=os.path.join(os.path.dirname(__file__), "..", "results"))
args = ap.parse_args()
logs = os.path.abspath(args.logs)
stamp = os.path.basename(logs.rstrip("/")).replace("flatness_", "")
results = os.path.abspath(args.results)
os.makedirs(results, exist_ok=True)

settings = read_settings(logs)

runs = []  # code, N, par (threads or ranks), rep, rate, resident_kB (engine)
for path in sorted(glob.glob(os.path.join(logs, "engine_x*_t*_r*.json"))):
    m = re.search(r"engine_x(\d+)_t(\d+)_r(\d+)\.json$", path)
    row = json.load(open(path))["rows"][0]
    runs.append(dict(code="engine", N=row["N"], par=int(m.group(2)), rep=int(m.group(3)),
                     rate=row["median_particle_steps_per_s"], resident_kB=row["resident_kB"],
                     z=row["z_end"]))
for path in sorted(glob.glob(os.path.join(logs, "lammps_x*_np*_r*.log"))):
    m = re.search(r"lammps_x(\d+)_np(\d+)_r(\d+)\.log$", path)
    text = open(path, errors="replace").read()
    i, j = text.find("PEER_TIMED_BEGIN"), text.find("PEER_TIMED_END")
    lm = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms",
                   text[i:j]) if i >= 0 and j >= 0 else None
    if not lm:
        print("incomplete:", path)
        continue
    loop, steps, natoms = float(lm.group(1)), int(lm.group(3)), int(lm.group(4))
    runs.append(dict(code="lammps", N=natoms, par=int(m.group(2)), rep=int(m.group(3)),
                     rate=natoms * steps / loop))

memory = {}  # threads -> {working set bytes: [GB/s per rep]}
for path in sorted(glob.glob(os.path.join(logs, "memory_t*_r*.json"))):
    t = int(re.search(r"memory_t(\d+)_r", path).group(1))
    for row in json.load(open(path))["rows"]:
        memory.setdefault(t, {}).setdefault(row["working_set_bytes"], []).append(row["bandwidth_GBs"])
curve = {t: sorted((ws, statistics.median(v)) for ws, v in d.items()) for t, d in memory.items()}


def bandwidth_at(t, ws):
    """Triad bandwidth at working set ws, interpolated in log-log between measured sizes."""
    c = curve.get(t)
    if not c:
        return None
    if ws <= c[0][0]:
        return c[0][1]
    for (w0, b0), (w1, b1) in zip(c, c[1:]):
        if ws <= w1:
            a = math.log(ws / w0) / math.log(w1 / w0)
            return math.exp(math.log(b0) + a * (math.log(b1) - math.log(b0)))
    return c[-1][1]


series = {}
for r in runs:
    series.setdefault((r["code"], r["par"]), {}).setdefault(r["N"], []).append(r)
summary = []
for (code, par), by_n in sorted(series.items()):
    sizes = sorted(by_n)
    base = statistics.median(x["rate"] for x in by_n[sizes[0]])
    for n in sizes:
        med = statistics.median(x["rate"] for x in by_n[n])
        row = dict(code=code, par=par, N=n, reps=len(by_n[n]), median_rate=med,
                   rates=[x["rate"] for x in by_n[n]], relative_to_smallest=med / base)
        if code == "engine":
            kb = statistics.median(x["resident_kB"] for x in by_n[n])
            row["resident_bytes"] = kb * 1024
            bw = bandwidth_at(par, kb * 1024)
            kb0 = statistics.median(x["resident_kB"] for x in by_n[sizes[0]])
            bw0 = bandwidth_at(par, kb0 * 1024)
            if bw and bw0:
                row["triad_at_resident_relative_to_smallest"] = bw / bw0
        summary.append(row)

out = dict(benchmark="flatness_sweep", settings=settings, runs=runs, summary=summary,
           memory_curve={str(t): [dict(working_set_bytes=w, bandwidth_GBs=b) for w, b in c]
                         for t, c in curve.items()})


def write_whole(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


write_whole(os.path.join(results, "flatness_%s.json" % stamp), json.dumps(out, indent=1))

lines = ["# Cost per particle-step against N at the same work per particle (%s)" % stamp, "",
         "The N = %s packing tiled %s times (periodic replicas: the same neighbours, contacts and "
         "rebuilds per particle at every N); engine physics %s, LAMMPS %s; %s repetitions, "
         "interleaved; medians in M particle-steps/s, and relative to the smallest tiling. "
         "Triad: the machine's triad bandwidth at the engine's resident memory of that N, relative "
         "to the smallest (perf/bench_memory_curve.cpp)."
         % (settings.get("base"), settings.get("factors"), settings.get("physics"),
            settings.get("model"), settings.get("reps")), "",
         "| code | threads / ranks | N | M/s | relative | resident MB | triad relative |",
         "|---|---|---|---|---|---|---|"]
for r in summary:
    lines.append("| %s | %d | %d | %.2f | %.3f | %s | %s |" % (
        r["code"], r["par"], r["N"], r["median_rate"] / 1e6, r["relative_to_smallest"],
        "%.1f" % (r["resident_bytes"] / 1e6) if "resident_bytes" in r else "",
        "%.3f" % r["triad_at_resident_relative_to_smallest"]
        if "triad_at_resident_relative_to_smallest" in r else ""))
write_whole(os.path.join(results, "flatness_%s.md" % stamp), "\n".join(lines) + "\n")

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib missing: no chart")
else:
    def finish(ax, xlabel, ylabel, title):
        ax.set_xscale("log", base=2)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)

    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.6))
    for (code, par), by_n in sorted(series.items()):
        rows = [r for r in summary if r["code"] == code and r["par"] == par]
        a.plot([r["N"] for r in rows], [r["relative_to_smallest"] for r in rows],
               "o-" if code == "engine" else "s--",
               label=("engine, %d thread(s)" if code == "engine" else
                      "LAMMPS " + settings.get("model", "") + ", %d rank(s)") % par)
    a.axhline(0.85, color="grey", lw=0.8, ls=":")
    a.text(int(settings.get("base", 4096)), 0.86, "0.85", color="grey", fontsize=8)
    finish(a, "N (tilings of one packing)", "particle-steps/s relative to the smallest N",
           "same work per particle, growing working set")
    for t, c in sorted(curve.items()):
        b.plot([w / 2**20 for w, _ in c], [g for _, g in c], label="triad, %d thread(s)" % t)
    for r in summary:
        if r["code"] == "engine" and r["par"] == min(p for _, p in series if _ == "engine"):
            b.axvline(r["resident_bytes"] / 2**20, color="grey", lw=0.6, ls=":")
    finish(b, "working set (MiB); dotted: the engine's resident memory at each N", "GB/s",
           "the machine's memory curve")
    fig.tight_layout()
    tmp = os.path.join(results, "flatness_%s.png.tmp" % stamp)
    fig.savefig(tmp, dpi=110, format="png")
    os.replace(tmp, os.path.join(results, "flatness_%s.png" % stamp))
print("wrote", os.path.join(results, "flatness_%s.{json,md,png}" % stamp))
