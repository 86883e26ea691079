"""Charts from the chain benchmark's result files:
   /usr/bin/python3 perf/plot_chain.py perf/results/chain_1t.json perf/results/chain_2t.json
writes perf/results/chain_error_vs_cost.png and perf/results/chain_throughput.png."""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

runs = [json.load(open(p)) for p in sys.argv[1:]]
outdir = os.path.dirname(os.path.abspath(sys.argv[1]))


def save(fig, name):
    path = os.path.join(outdir, name)
    tmp = os.path.join(outdir, "." + name + ".partial")
    fig.tight_layout()
    fig.savefig(tmp, dpi=120, format="png")
    os.replace(tmp, path)


# Error against the exact eigenmode solution versus cost (last file: the most threads).
rows = runs[-1]["error_vs_cost"]
fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.6))
for kernel, style in (("linear", "o-"), ("hertz", "s--")):
    r = [x for x in rows if x["kernel"] == kernel]
    cost = [x["seconds_per_unit_time_per_realization"] * 1e6 for x in r]
    a1.loglog(cost, [x["relative_displacement_error"] for x in r], style, label=f"{kernel} kernel")
    a2.loglog([x["dt"] for x in r], [x["relative_energy_error"] for x in r], style, label=f"{kernel} kernel")
    for x, c in zip(r, cost):
        a1.annotate(f"{x['dt']:g}", (c, x["relative_displacement_error"]), fontsize=6)
a1.set_xlabel("cost: us of compute per unit time per realization (N = 256)")
a1.set_ylabel("|u - u_exact| / |u_exact| at t = 100")
a1.set_title("labels: dt")
dts = sorted({x["dt"] for x in rows})
ref = [x for x in rows if x["kernel"] == "linear" and x["dt"] == dts[len(dts) // 2]][0]
a2.loglog(dts, [ref["relative_energy_error"] * (d / ref["dt"]) ** 2 for d in dts], "k:", lw=0.8, label="~ dt^2")
a2.axvline(2 / (2 * 1.5 ** 0.5), color="r", lw=0.8, label="2/omega_max (ordered)")
a2.set_xlabel("dt")
a2.set_ylabel("relative energy error")
a1.legend(fontsize=7)
a2.legend(fontsize=7)
save(fig, "chain_error_vs_cost.png")

fig, ax = plt.subplots(figsize=(6.4, 3.6))
labels, values = [], []
for run in runs:
    threads = run["machine"]["kokkos_concurrency"]
    for row in run["throughput"]:
        if "refused" in row:
            continue
        # Older result files name the law "kernel"; newer ones name law and kernel.
        name = f"{row['law']}\n{row['kernel']}" if "law" in row else row["kernel"]
        labels.append(f"{name}\n{threads} thr")
        values.append(row["median_bead_steps_per_second"] / 1e6)
ax.bar(range(len(values)), values)
ax.set_xticks(range(len(values)), labels, fontsize=7)
ax.set_ylabel("million bead-steps / s")
ax.set_title(f"{runs[0]['throughput'][0]['realizations']} x {runs[0]['throughput'][0]['beads']} chains")
save(fig, "chain_throughput.png")
