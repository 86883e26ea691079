#!/usr/bin/python3
"""Summarise one run of perf/peer/run_peer_bench.sh.

    summarize.py perf/peer/logs/<stamp> [more run directories] [--results perf/results]

Reads the engine's JSON files and LAMMPS' logs of the run directories (several: e.g. a
separate run for N = 262144 with fewer configurations; the first one names the result) and
writes
  <results>/peer_<stamp>.json   every repetition, medians, ratios, cross-check, memory
  <results>/peer_latest.md      the tables
  <results>/peer_latest.png     throughput per configuration, cost scaling with N, ratios
Throughput is particle-steps per second of the timed window (N * steps / time): the
engine's own timer around its steps, LAMMPS' "Loop time" of the timed run.
"""
import argparse
import glob
import json
import os
import re
import statistics

from peer_logs import read_settings

ap = argparse.ArgumentParser()
ap.add_argument("logs", nargs="+")
ap.add_argument("--results", default=os.path.join(os.path.dirname(__file__), "..", "results"))
args = ap.parse_args()
dirs = [os.path.abspath(x) for x in args.logs]
logs = dirs[0]
stamp = os.path.basename(logs.rstrip("/"))
results = os.path.abspath(args.results)
os.makedirs(results, exist_ok=True)

settings = read_settings(logs)

# Which engine physics is timed against which LAMMPS style.
PAIRS = [
    # (engine physics, LAMMPS model, role)
    ("friction", "hooke_mass", "fastest LAMMPS style (gran/hooke/history, mass-scaled dashpots)"),
    ("friction", "hooke_abs", "same formula (pair granular, absolute dashpots)"),
    ("frictionless", "frictionless_mass", "fastest LAMMPS style (gran/hooke, mu 0)"),
    ("frictionless", "frictionless_abs", "same formula (pair granular, mu 0)"),
    ("hertz_tsuji", "hertz_mass", "fastest LAMMPS Hertz style (gran/hertz/history, mass-scaled dashpots)"),
    ("hertz_tsuji", "hertz_tsuji", "same formula (pair granular hertz/material, mindlin, tsuji)"),
]
# The cross-check needs the same formula: absolute dashpots on both sides.
CROSS = [("friction", "hooke_abs"), ("frictionless", "frictionless_abs"), ("hertz_tsuji", "hertz_tsuji")]


def run_of(path):  # the run directory a log belongs to
    return os.path.basename(os.path.dirname(path))


def rss_kb(text):
    return [int(x) for x in re.findall(r"PEER_RSS_KB (\d+)", text)]


runs = []
machine = None
for path in sorted(sum((glob.glob(os.path.join(x, "engine_*.json")) for x in dirs), [])):
    m = re.match(r"engine_(\w+?)_N(\d+)_t(\d+)_r(\d+)\.json$", os.path.basename(path))
    if not m:
        continue
    d = json.load(open(path))
    machine = machine or d["machine"]
    row = d["rows"][0]
    log = open(path[:-5] + ".log", errors="replace").read() if os.path.exists(path[:-5] + ".log") else ""
    rss = rss_kb(log)
    runs.append(dict(code="engine", config=m.group(1), N=int(m.group(2)), par=int(m.group(3)),
                     rep=int(m.group(4)), run=run_of(path), pps=row["median_particle_steps_per_s"],
                     ke_initial=row.get("ekin_translational_initial_J"),
                     ke_warmup=row["ekin_translational_after_warmup_J"],
                     ke_end=row["ekin_translational_after_timed_run_J"],
                     z_initial=row.get("z_initial"), z_end=row["z_end"],
                     rss_kB=sum(rss) if rss else row.get("resident_kB"),
                     vmhwm_kB=row.get("resident_kB"),
                     bytes_per_particle_step=row["bytes_per_particle_step"],
                     profile=row["profile_fraction"],
                     neighbor_builds=row["neighbor_builds_in_timed_window"],
                     neighbors_full_list=row["neighbors_per_particle_full_list"]))

for path in sorted(sum((glob.glob(os.path.join(x, "lammps_*.log")) for x in dirs), [])):
    m = re.match(r"lammps_(\w+?)_N(\d+)_np(\d+)_r(\d+)\.log$", os.path.basename(path))
    if not m:
        continue
    text = open(path, errors="replace").read()
    i = text.find("PEER_TIMED_BEGIN")
    j = text.find("PEER_TIMED_END")
    if i < 0 or j < 0:
        print("incomplete:", path)
        continue
    timed = text[i:j]
    lm = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", timed)
    if not lm:
        continue
    loop, steps, natoms = float(lm.group(1)), int(lm.group(3)), int(lm.group(4))
    states = {s: dict(re.findall(r"(\w+)=([0-9.eE+-]+)", rest))
              for s, rest in re.findall(r"PEER_STATE stage=(\w+) (.*)", text)}
    prof = {}
    for sec in ("Pair", "Neigh", "Comm", "Output", "Modify", "Other"):
        pm = re.search(r"^%s\s*\|.*\|\s*([0-9.]+)\s*$" % sec, timed, re.M)
        if pm:
            prof[sec] = float(pm.group(1)) / 100
    nb = re.search(r"Neighbor list builds = (\d+)", timed)
    rss = rss_kb(text + (open(path + ".rss").read() if os.path.exists(path + ".rss") else ""))
    if len(rss) != int(m.group(3)):  # a rank's figure missing: no sum to report
        print("memory of %s: %d figures for %s ranks, left out" % (path, len(rss), m.group(3)))
        rss = []
    runs.append(dict(code="lammps", config=m.group(1), N=int(m.group(2)), par=int(m.group(3)),
                     rep=int(m.group(4)), run=run_of(path), pps=natoms * steps / loop, loop_s=loop,
                     ke_initial=float(states["start"]["ke"]),
                     ke_warmup=float(states["warmup"]["ke"]), ke_end=float(states["end"]["ke"]),
                     z_initial=float(states["start"]["z"]), z_end=float(states["end"]["z"]),
                     rss_kB=sum(rss) if rss else None, rss_per_rank_kB=rss, profile=prof,
                     neighbor_builds=int(nb.group(1)) if nb else None))

triad = {}
for path in sorted(sum((glob.glob(os.path.join(x, "triad_t*_r*.json")) for x in dirs), [])):
    m = re.match(r"triad_t(\d+)_r(\d+)\.json$", os.path.basename(path))
    d = json.load(open(path))
    machine = machine or d["machine"]
    triad.setdefault(int(m.group(1)), []).append(d["triad_bandwidth_GBs"])
triad_best = {t: max(v) for t, v in triad.items()}  # STREAM convention: best of the runs


def group(code, config, N, par):
    return [r for r in runs if (r["code"], r["config"], r["N"], r["par"]) == (code, config, N, par)]


def med(rs, key="pps"):
    v = [r[key] for r in rs if r.get(key) is not None]
    return statistics.median(v) if v else None


sizes = sorted({r["N"] for r in runs})
pars = sorted({r["par"] for r in runs})
summary = []
for code, config in sorted({(r["code"], r["config"]) for r in runs}):
    for N in sizes:
        for p in pars:
            rs = group(code, config, N, p)
            if not rs:
                continue
            v = [r["pps"] for r in rs]
            s = dict(code=code, config=config, N=N, par=p, reps=len(rs), median_pps=med(rs),
                     min_pps=min(v), max_pps=max(v), spread=(max(v) - min(v)) / med(rs),
                     median_rss_kB=med(rs, "rss_kB"))
            if s["median_rss_kB"]:
                s["rss_bytes_per_particle"] = s["median_rss_kB"] * 1024 / N
            if code == "engine":
                bpps = rs[0]["bytes_per_particle_step"]
                s["bytes_per_particle_step"] = bpps
                s["achieved_GBs"] = s["median_pps"] * bpps / 1e9
                if p in triad_best:
                    s["fraction_of_triad_same_threads"] = s["achieved_GBs"] / triad_best[p]
                if triad_best:
                    s["fraction_of_triad_machine"] = s["achieved_GBs"] / max(triad_best.values())
                s["profile"] = {k: statistics.median([r["profile"][k] for r in rs]) for k in rs[0]["profile"]}
            else:
                keys = rs[0]["profile"].keys()
                s["profile"] = {k: statistics.median([r["profile"].get(k, 0) for r in rs]) for k in keys}
            s["neighbor_builds"] = rs[0]["neighbor_builds"]
            summary.append(s)


def find(code, config, N, p):
    for s in summary:
        if (s["code"], s["config"], s["N"], s["par"]) == (code, config, N, p):
            return s
    return None


ratios = []
for phys, model, role in PAIRS:
    for N in sizes:
        for p in pars:
            a, b = find("engine", phys, N, p), find("lammps", model, N, p)
            if a and b:
                # Repetition by repetition as well: each engine run against the LAMMPS run of the
                # same repetition of the same run directory (minutes apart, so in a like state
                # of the machine); the ratio of the medians above pairs no two runs.
                lam = {(r["run"], r["rep"]): r["pps"] for r in group("lammps", model, N, p)}
                pr = [r["pps"] / lam[(r["run"], r["rep"])] for r in group("engine", phys, N, p)
                      if (r["run"], r["rep"]) in lam]
                ratios.append(dict(engine=phys, lammps=model, role=role, N=N, threads_vs_ranks=p,
                                   engine_pps=a["median_pps"], lammps_pps=b["median_pps"],
                                   ratio=a["median_pps"] / b["median_pps"], pair_ratios=pr,
                                   pair_ratio_median=statistics.median(pr) if pr else None))

cross = []
for phys, model in CROSS:
    for N in sizes:
        a = [r for r in runs if r["code"] == "engine" and r["config"] == phys and r["N"] == N and r["par"] == 1]
        b = [r for r in runs if r["code"] == "lammps" and r["config"] == model and r["N"] == N and r["par"] == 1]
        if not a or not b:
            continue
        a, b = a[-1], b[-1]  # the latest run (1 thread / 1 rank runs are deterministic)
        c = dict(engine=phys, lammps=model, N=N)
        ok = True
        for q in ("ke_initial", "ke_warmup", "ke_end", "z_initial", "z_end"):
            if a.get(q) is None or b.get(q) is None:
                continue
            rel = (a[q] - b[q]) / b[q]
            c[q] = dict(engine=a[q], lammps=b[q], rel_diff=rel)
            if q in ("ke_warmup", "ke_end", "z_end") and abs(rel) > 0.01:
                ok = False
        c["within_1_percent"] = ok
        cross.append(c)

memory = []
for code, config in sorted({(s["code"], s["config"]) for s in summary}):
    for p in pars:
        ss = [find(code, config, N, p) for N in sizes]
        ss = [s for s in ss if s and s.get("median_rss_kB")]
        if len(ss) >= 2:
            a, b = ss[0], ss[-1]
            memory.append(dict(code=code, config=config, par=p, N_small=a["N"], N_large=b["N"],
                               marginal_bytes_per_particle=(b["median_rss_kB"] - a["median_rss_kB"]) * 1024 / (b["N"] - a["N"])))

out = dict(benchmark="peer_comparison", stamp=stamp, run_directories=[os.path.basename(x) for x in dirs], machine=machine, settings=settings,
           triad_GBs=triad, triad_best_GBs=triad_best, runs=runs, summary=summary, ratios=ratios,
           cross_check=cross, memory=memory)
json_path = os.path.join(results, "peer_%s.json" % stamp)
with open(json_path, "w") as f:
    json.dump(out, f, indent=1)

# ---- markdown -------------------------------------------------------------------------------
M = lambda x: "%.2f" % (x / 1e6)
L = []
L.append("# Peer comparison: engine vs LAMMPS (run %s)\n" % stamp)
if machine:
    L.append("Machine: %s, %s hardware threads; %s; Kokkos %s. LAMMPS %s (Debian, MPI only). "
             "%s repetitions interleaved, %s timed steps after %s warm-up steps, dt 4.5e-9 s, skin 0.2 mm.\n"
             % (machine.get("cpu_model"), machine.get("hardware_threads"), machine.get("compiler"),
                machine.get("kokkos_execution_space"), settings.get("lammps_version"),
                settings.get("reps"), settings.get("steps"), settings.get("warmup")))
if settings.get("walls") == "z":
    L.append("Walled box: the z faces of each packing are flat walls with the pair's law (LAMMPS `fix "
             "wall/gran`, the engine's planar walls), the packing `packing_walls_<N>.data` made from the "
             "periodic one by perf/peer/walls.lmp (particles crossing a face removed, then relaxed "
             "against the walls); N names the periodic packing it was cut from.\n")
L.append("## Throughput (median, million particle-steps/s) and ratio engine/LAMMPS\n")
L.append("| engine physics | LAMMPS style | N | engine 1 thread | LAMMPS 1 rank | ratio 1:1 | engine 2 threads | LAMMPS 2 ranks | ratio 2:2 |")
L.append("|---|---|---|---|---|---|---|---|---|")
for phys, model, role in PAIRS:
    for N in sizes:
        cells = []
        for p in (1, 2):
            a, b = find("engine", phys, N, p), find("lammps", model, N, p)
            cells += [M(a["median_pps"]) if a else "-", M(b["median_pps"]) if b else "-",
                      "**%.2f**" % (a["median_pps"] / b["median_pps"]) if a and b else "-"]
        L.append("| %s | %s (%s) | %d | %s |" % (phys, model, role.split(" (")[0], N, " | ".join(cells)))
L.append("\nRatio repetition by repetition against the fastest style (each engine run against the "
         "LAMMPS run of the same repetition):\n")
L.append("| engine physics | LAMMPS style | N | threads : ranks | ratios | median | min |")
L.append("|---|---|---|---|---|---|---|")
for r in ratios:
    if r["role"].startswith("fastest") and r["pair_ratios"]:
        L.append("| %s | %s | %d | %d : %d | %s | %.2f | %.2f |" % (
            r["engine"], r["lammps"], r["N"], r["threads_vs_ranks"], r["threads_vs_ranks"],
            ", ".join("%.2f" % x for x in r["pair_ratios"]), r["pair_ratio_median"], min(r["pair_ratios"])))
L.append("\nSpread of the repetitions ((max - min)/median):\n")
L.append("| code | configuration | N | threads/ranks | reps | median | min..max | spread |")
L.append("|---|---|---|---|---|---|---|---|")
for s in summary:
    L.append("| %s | %s | %d | %d | %d | %s | %s..%s | %.0f %% |" % (s["code"], s["config"], s["N"], s["par"], s["reps"],
             M(s["median_pps"]), M(s["min_pps"]), M(s["max_pps"]), 100 * s["spread"]))
L.append("\n## Physics cross-check (same data file, 1 thread / 1 rank; KE = translational kinetic energy in J)\n")
L.append("| engine | LAMMPS | N | quantity | engine | LAMMPS | rel. diff |")
L.append("|---|---|---|---|---|---|---|")
for c in cross:
    for q in ("ke_initial", "ke_warmup", "ke_end", "z_initial", "z_end"):
        if q in c:
            L.append("| %s | %s | %d | %s | %.6g | %.6g | %+.3f %% |" % (c["engine"], c["lammps"], c["N"], q,
                     c[q]["engine"], c[q]["lammps"], 100 * c[q]["rel_diff"]))
    L.append("| %s | %s | %d | **within 1 %%** | | | %s |" % (c["engine"], c["lammps"], c["N"], "yes" if c["within_1_percent"] else "**NO**"))
L.append("\n## Memory: peak resident set / N (bytes per particle; MPI ranks summed)\n")
L.append("| code | configuration | threads/ranks | " + " | ".join("N = %d" % N for N in sizes) + " | marginal (large - small) |")
L.append("|---|---|---|" + "---|" * len(sizes) + "---|")
for code, config in sorted({(s["code"], s["config"]) for s in summary}):
    for p in pars:
        cells = []
        for N in sizes:
            s = find(code, config, N, p)
            cells.append("%.0f" % s["rss_bytes_per_particle"] if s and s.get("rss_bytes_per_particle") else "-")
        mm = [x for x in memory if (x["code"], x["config"], x["par"]) == (code, config, p)]
        cells.append("%.0f" % mm[0]["marginal_bytes_per_particle"] if mm else "-")
        L.append("| %s | %s | %d | %s |" % (code, config, p, " | ".join(cells)))
L.append("\n## Memory bandwidth and profile (engine)\n")
L.append("Triad bandwidth (best of the runs): " + ", ".join("%d thread(s) %.1f GB/s" % (t, v) for t, v in sorted(triad_best.items())) + ".\n")
L.append("| physics | N | threads | bytes/particle-step | achieved GB/s | fraction of triad (same threads) | fraction of machine triad | force | integrate | neighbour | rebuilds |")
L.append("|---|---|---|---|---|---|---|---|---|---|---|")
for s in summary:
    if s["code"] != "engine":
        continue
    pr = s["profile"]
    L.append("| %s | %d | %d | %.0f | %.2f | %.1f %% | %.1f %% | %.0f %% | %.0f %% | %.0f %% | %s |" % (
        s["config"], s["N"], s["par"], s["bytes_per_particle_step"], s["achieved_GBs"],
        100 * s.get("fraction_of_triad_same_threads", float("nan")), 100 * s.get("fraction_of_triad_machine", float("nan")),
        100 * pr["force"], 100 * pr["integrate"], 100 * pr["neighbor"], s["neighbor_builds"]))
L.append("\nLAMMPS profile of the timed run (share of loop time):\n")
L.append("| style | N | ranks | Pair | Neigh | Comm | Modify | Other | rebuilds |")
L.append("|---|---|---|---|---|---|---|---|---|")
for s in summary:
    if s["code"] != "lammps":
        continue
    pr = s["profile"]
    L.append("| %s | %d | %d | %s | %s |" % (s["config"], s["N"], s["par"], " | ".join(
        "%.0f %%" % (100 * pr.get(k, 0)) for k in ("Pair", "Neigh", "Comm", "Modify", "Other")), s["neighbor_builds"]))
L.append("\nRaw data: `perf/results/peer_%s.json`.\n" % stamp)
with open(os.path.join(results, "peer_latest.md"), "w") as f:
    f.write("\n".join(L))

# ---- chart -------------------------------------------------------------------------------
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib missing (Debian package python3-matplotlib): no chart")
else:
    fig, ax = plt.subplots(1, 3, figsize=(17, 5.2))
    configs = [("engine", "friction"), ("lammps", "hooke_mass"), ("lammps", "hooke_abs"),
               ("engine", "frictionless"), ("lammps", "frictionless_mass"), ("lammps", "frictionless_abs"),
               ("engine", "hertz_tsuji"), ("lammps", "hertz_mass"), ("lammps", "hertz_tsuji")]
    colors = {"friction": "C0", "hooke_mass": "C1", "hooke_abs": "C3", "frictionless": "C2",
              "frictionless_mass": "C4", "frictionless_abs": "C5", "hertz_mass": "C6",
              "hertz_tsuji": "C7"}
    # (a) medians at the largest two sizes, grouped by configuration
    labels, x = [], 0
    for N in sizes:
        for code, config in configs:
            for p in pars:
                s = find(code, config, N, p)
                if not s:
                    continue
                ax[0].bar(x, s["median_pps"] / 1e6, color=colors[config], alpha=1.0 if p == 2 else 0.55)
                ax[0].plot([x, x], [s["min_pps"] / 1e6, s["max_pps"] / 1e6], "k-", lw=1)
                labels.append("%s %s\n%s%d" % ("eng" if code == "engine" else "LMP", config, "t" if code == "engine" else "r", p))
                x += 1
        x += 1
        labels.append("")
    ax[0].set_xticks(range(len(labels)))
    ax[0].set_xticklabels(labels, rotation=90, fontsize=6)
    ax[0].set_ylabel("million particle-steps / s (median, bar = min..max)")
    ax[0].set_title("Throughput, N = " + ", ".join(map(str, sizes)) + " (left to right)")
    # (b) scaling with N
    for code, config in configs:
        for p in pars:
            pts = [(N, find(code, config, N, p)) for N in sizes]
            pts = [(N, s["median_pps"] / 1e6) for N, s in pts if s]
            if len(pts) < 1:
                continue
            ax[1].plot([a for a, _ in pts], [b for _, b in pts], "o-" if code == "engine" else "s--",
                       color=colors[config], alpha=1.0 if p == 2 else 0.5,
                       label="%s %s %d%s" % (code, config, p, "t" if code == "engine" else "r"))
    ax[1].set_xscale("log", base=2)
    ax[1].set_xlabel("N")
    ax[1].set_ylabel("million particle-steps / s")
    ax[1].set_title("Cost scaling: flat line = O(N) cost per step")
    ax[1].legend(fontsize=6, ncol=2)
    ax[1].set_ylim(bottom=0)
    # (c) ratios
    x = 0
    ticks = []
    for r in ratios:
        ax[2].bar(x, r["ratio"], color=colors[r["lammps"]], alpha=1.0 if r["threads_vs_ranks"] == 2 else 0.55)
        ticks.append("%s/%s\nN=%d %d:%d" % (r["engine"], r["lammps"], r["N"], r["threads_vs_ranks"], r["threads_vs_ranks"]))
        x += 1
    ax[2].axhline(2.0, color="k", ls="--", lw=1, label="target 2x")
    ax[2].axhline(1.0, color="gray", ls=":", lw=1)
    ax[2].set_xticks(range(len(ticks)))
    ax[2].set_xticklabels(ticks, rotation=90, fontsize=6)
    ax[2].set_ylabel("engine / LAMMPS (medians)")
    ax[2].set_title("Speed ratio (threads vs ranks)")
    ax[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(results, "peer_latest.png"), dpi=110)
print("wrote", json_path, "and peer_latest.md / peer_latest.png in", results)
