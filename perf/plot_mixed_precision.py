#!/usr/bin/python3
"""Chart of the mixed-precision force pass's accuracy cost beside its speed and memory
(docs/mixed_precision.md), from three result files of one machine:

    plot_mixed_precision.py --energy perf/results/mixed_precision_energy_vs_dt.json
                            --probe perf/results/mixed_precision.json
                            --throughput perf/results/mixed_precision_throughput_1t.json
                            [--out perf/results/mixed_precision.png]

--energy: bench_dem_energy_vs_dt --precision double,mixed; --probe: bench_mixed_precision;
--throughput: bench_dem_throughput rows of the same physics and size in double (one-pass and
two-pass kernels) and in mixed precision (bench_dem_throughput --two-pass / --mixed, the row
files concatenated as a JSON list).
Panels: energy error against dt/t_c in both precisions; the trajectory cross-check (kinetic
energy and largest position difference of the mixed run and of a double run moved by half a
fixed-point step, against the double run); the moduli probe's relative difference against
the strain amplitude; speed and memory per particle.
"""
import argparse
import json
import os

here = os.path.dirname(os.path.abspath(__file__))
res = os.path.join(here, "results")
ap = argparse.ArgumentParser()
ap.add_argument("--energy", default=os.path.join(res, "mixed_precision_energy_vs_dt.json"))
ap.add_argument("--probe", default=os.path.join(res, "mixed_precision.json"))
ap.add_argument("--throughput", default=os.path.join(res, "mixed_precision_throughput_1t.json"))
ap.add_argument("--out", default=os.path.join(res, "mixed_precision.png"))
args = ap.parse_args()

energy = json.load(open(args.energy))
probe = json.load(open(args.probe))
runs = json.load(open(args.throughput))
if isinstance(runs, dict):
    runs = [runs]

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

fig, ax = plt.subplots(1, 4, figsize=(22, 5))

# 1. energy error against the time step
for prec, style in (("double", "o-"), ("mixed", "s--")):
    rows = [r for r in energy["rows"] if r.get("precision") == prec and r["status"] == "stable"]
    ax[0].loglog([r["fraction"] for r in rows], [r["max_relative_energy_error"] for r in rows], style,
                 label=prec)
ax[0].axvline(energy["engine_guard_fraction"], color="C2", ls="--", lw=1, label="engine dt guard t_c/10")
ax[0].set_xlabel("dt / t_c")
ax[0].set_ylabel("max |E(t) - E(0)| / E(0) over %g t_c" % energy["simulated_time_in_tc"])
ax[0].set_title("Energy conservation, undamped packing, N = %d" % energy["N"])
ax[0].legend(fontsize=8)
ax[0].grid(True, which="both", alpha=0.3)

# 2. trajectory cross-check
t = probe["trajectory"]
steps = [r["step"] for r in t][1:]
for key, lab, c in (("ekin_relative_difference_mixed", "|dE_kin|/E_kin, mixed", "C0"),
                    ("ekin_relative_difference_moved_half_step", "|dE_kin|/E_kin, double moved 1/2 step", "C1"),
                    ("max_position_difference_mixed", "max |dx| (mm), mixed", "C2"),
                    ("max_position_difference_moved_half_step", "max |dx| (mm), double moved 1/2 step", "C3")):
    ax[1].semilogy(steps, [max(abs(r[key]), 1e-18) for r in t[1:]], "o-" if "mixed" in lab else "x--",
                   color=c, label=lab, ms=4)
ax[1].axhline(probe["fixed_point_step"], color="k", lw=0.8, ls=":", label="fixed-point step (mm)")
ax[1].set_xlabel("step")
ax[1].set_ylabel("difference from the double run")
ax[1].set_title("Frictional packing, N = %d: against the double run" % probe["N"])
ax[1].legend(fontsize=7)
ax[1].grid(True, which="both", alpha=0.3)

# 3. moduli probe
for name, mk in (("K (isotropic)", "o-"), ("G (pure shear)", "s-")):
    rows = [r for r in probe["moduli_probe"] if r["modulus"] == name]
    ax[2].loglog([r["strain"] for r in rows], [max(abs(r["relative_difference"]), 1e-16) for r in rows], mk,
                 label=name)
ax[2].set_xlabel("strain amplitude")
ax[2].set_ylabel("|M_mixed - M_double| / M_double")
ax[2].set_title("Quasi-static moduli probe")
ax[2].legend(fontsize=8)
ax[2].grid(True, which="both", alpha=0.3)


# 4. speed and memory
def label(r):
    return "%s\n%s" % (r["precision"].split(" ")[0], r["force_kernel"])


rows = [r for run in runs for r in run["rows"]]
names = [label(r) for r in rows]
speed = [r["median_particle_steps_per_s"] / 1e6 for r in rows]
mem = [r.get("peak_device_bytes_per_particle", 0) for r in rows]
x = list(range(len(rows)))
ax[3].bar([i - 0.2 for i in x], speed, 0.4, color="C0", label="M particle-steps/s")
ax3 = ax[3].twinx()
ax3.bar([i + 0.2 for i in x], mem, 0.4, color="C1", label="peak bytes per particle")
for i in x:
    ax[3].text(i - 0.2, speed[i], "%.2f" % speed[i], ha="center", va="bottom", fontsize=7)
    ax3.text(i + 0.2, mem[i], "%.0f" % mem[i], ha="center", va="bottom", fontsize=7)
ax[3].set_xticks(x)
ax[3].set_xticklabels(names, fontsize=7)
ax[3].set_ylabel("M particle-steps/s (median)", color="C0")
ax3.set_ylabel("peak bytes per particle", color="C1")
r0 = rows[0]
ax[3].set_title("%s, N = %d, %s thread(s)" % (r0["physics"], r0["N"], r0["threads"]))
fig.tight_layout()
fig.savefig(args.out, dpi=110)
print("wrote", args.out)
