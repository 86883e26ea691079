#!/usr/bin/python3
"""Chart of bench_dem_throughput results against N: median particle-steps per second per
physics switch, one line per result file (e.g. a backend before and after a change).

    /usr/bin/python3 perf/plot_throughput_vs_n.py OUT.png LABEL=FILE.json [LABEL=FILE.json ...]
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main(args):
    if len(args) < 2 or any("=" not in a for a in args[1:]):
        sys.exit(__doc__)
    out = args[0]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    styles = {"friction": "o-", "frictionless": "s--"}
    for spec in args[1:]:
        label, path = spec.split("=", 1)
        with open(path) as f:
            data = json.load(f)
        by_physics = {}
        for r in data["rows"]:
            by_physics.setdefault(r["physics"], []).append(
                (r["N"], r["median_particle_steps_per_s"]))
        for phys, pts in sorted(by_physics.items()):
            pts.sort()
            ax.plot([p[0] for p in pts], [p[1] for p in pts], styles.get(phys, "^-"),
                    label=f"{label}, {phys}")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("particles N (dense packing, phi = 0.64)")
    ax.set_ylabel("particle-steps per second (median)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main(sys.argv[1:])
