#!/usr/bin/python3
"""Chart of bench_dem_energy_vs_dt's result file.

    plot_dem_energy_vs_dt.py [perf/results/dem_energy_vs_dt.json] [--out perf/results/dem_energy_vs_dt.png]

Left: largest relative energy error over the run against dt/t_c (log-log), with a dt^2 fit
over the stable range up to dt/t_c = 0.1, the stability edges (pair 2/omega, network
2/omega_max of the initial contacts), the engine's dt guard and the default time steps;
unstable runs are drawn as crosses at the error where the run was stopped.
Middle: relative energy error against simulated time for a few time steps.
Right: wall-clock cost per contact time simulated, against dt/t_c.
Also prints the fitted exponent (and stores it in the JSON file as fit_exponent).
"""
import argparse
import json
import math
import os

here = os.path.dirname(os.path.abspath(__file__))
ap = argparse.ArgumentParser()
ap.add_argument("json", nargs="?", default=os.path.join(here, "results", "dem_energy_vs_dt.json"))
ap.add_argument("--out", default=None)
ap.add_argument("--fit-max", type=float, default=0.1, help="largest dt/t_c of the power-law fit")
args = ap.parse_args()
out = args.out or os.path.splitext(args.json)[0] + ".png"
d = json.load(open(args.json))
rows = d["rows"]
stable = [r for r in rows if r["status"] == "stable"]
unstable = [r for r in rows if r["status"] != "stable"]

# least-squares fit of log(err) = a + p log(dt/t_c) over the stable small-dt rows
fit = [r for r in stable if r["fraction"] <= args.fit_max and r["max_relative_energy_error"] > 0]
p = a = None
if len(fit) >= 2:
    xs = [math.log(r["fraction"]) for r in fit]
    ys = [math.log(r["max_relative_energy_error"]) for r in fit]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    p = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    a = my - p * mx
    d["fit_exponent"] = p
    d["fit_range_max_fraction"] = args.fit_max
    with open(args.json, "w") as f:
        json.dump(d, f, indent=1)
    print("energy error ~ (dt/t_c)^%.3f for dt/t_c <= %g" % (p, args.fit_max))
if unstable:
    print("first unstable dt/t_c: %g" % min(r["fraction"] for r in unstable))
print("largest stable dt/t_c: %g" % max(r["fraction"] for r in stable) if stable else "no stable run")

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

fig, ax = plt.subplots(1, 3, figsize=(17, 5))
f = [r["fraction"] for r in stable]
ax[0].loglog(f, [r["max_relative_energy_error"] for r in stable], "o-", color="C0", label="stable: max |E(t) - E(0)| / E(0)")
if unstable:
    ax[0].loglog([r["fraction"] for r in unstable], [max(r["max_relative_energy_error"], 1e-12) for r in unstable],
                 "x", color="C3", ms=10, mew=2, label="unstable: stopped by the guards")
if p is not None:
    fx = [min(f), args.fit_max]
    ax[0].loglog(fx, [math.exp(a) * x ** p for x in fx], "k--", lw=1, label="fit: slope %.2f" % p)
for key, style, lab in (("edge_fraction_pair", ":", "pair edge 2/omega"),
                        ("edge_fraction_network", "-.", "network edge 2/omega_max")):
    ax[0].axvline(d[key], color="C3", ls=style, lw=1.2, label="%s = %.2f t_c" % (lab, d[key]))
ax[0].axvline(d["engine_guard_fraction"], color="C2", ls="--", lw=1.2, label="engine dt guard t_c/10")
for k, dd in enumerate(d["default_time_steps"]):
    ax[0].axvline(dd["fraction"], color="C%d" % (4 + k), ls="-", lw=1, alpha=0.7,
                  label="default: %s (%.4f t_c)" % (dd["what"].split(":")[0], dd["fraction"]))
ax[0].set_xlabel("dt / t_c  (t_c = pi sqrt(m_red/k) of the lightest pair = %.3f us)" % d["contact_time_us"])
ax[0].set_ylabel("relative energy error over %g t_c" % d["simulated_time_in_tc"])
ax[0].set_title("Undamped dense packing, N = %d: energy error vs dt" % d["N"])
ax[0].legend(fontsize=6.5, loc="best")
ax[0].grid(True, which="both", alpha=0.3)

pick = [r for r in rows if r["fraction"] in (0.01, 0.05, 0.1, 0.3, 0.5)] + unstable[:1]
for r in pick:
    ax[1].plot(r["time_in_tc"], r["relative_energy_error"], label="dt/t_c = %g (%s)" % (r["fraction"], r["status"]))
ax[1].set_yscale("symlog", linthresh=1e-7)
ax[1].set_xlabel("simulated time / t_c")
ax[1].set_ylabel("(E(t) - E(0)) / E(0)")
ax[1].set_title("Energy error history")
ax[1].legend(fontsize=7)
ax[1].grid(True, alpha=0.3)

done = [r for r in rows if r.get("cost_s_per_tc_simulated")]
ax[2].loglog([r["fraction"] for r in done], [r["cost_s_per_tc_simulated"] for r in done], "o-", color="C1")
for r in done:
    if r["status"] != "stable":
        ax[2].plot(r["fraction"], r["cost_s_per_tc_simulated"], "x", color="C3", ms=10, mew=2)
ax[2].axvline(d["edge_fraction_network"], color="C3", ls="-.", lw=1.2)
for k, dd in enumerate(d["default_time_steps"]):
    ax[2].axvline(dd["fraction"], color="C%d" % (4 + k), ls="-", lw=1, alpha=0.7)
ax[2].set_xlabel("dt / t_c")
ax[2].set_ylabel("wall seconds per t_c simulated (%s threads)" % d["machine"].get("kokkos_concurrency"))
ax[2].set_title("Cost per unit simulated time (~ 1/dt)")
ax[2].grid(True, which="both", alpha=0.3)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
