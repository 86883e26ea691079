#!/usr/bin/python3
"""Charts of perf/gpu_full_size.sh's results: throughput against N (with the bandwidth the
engine's byte count and the minimal-traffic model imply), and device memory per particle
against N, split by array at the peak.

    perf/plot_gpu_full_size.py RESULTS_DIR [RESULTS_DIR_B]

Writes RESULTS_DIR/throughput_vs_n.png and RESULTS_DIR/memory_vs_n.png; with a second
directory (an 'after' run), both runs are drawn, the second solid.
"""
import glob
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(folder):
    out = []
    copy_bw = None
    for f in sorted(glob.glob(os.path.join(folder, "*.json"))):
        d = json.load(open(f))
        copy_bw = d.get("copy_bandwidth_GBs", copy_bw)
        out.extend(d["rows"])
    return out, copy_bw


def main():
    folders = sys.argv[1:]
    if not folders:
        sys.exit(__doc__)
    runs = [(f, *rows(f)) for f in folders]
    out_dir = folders[-1]

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for k, (folder, rs, _) in enumerate(runs):
        for phys, marker in (("friction", "o"), ("frictionless", "s")):
            sel = sorted((r for r in rs if r["physics"] == phys), key=lambda r: r["N"])
            if not sel:
                continue
            ax.plot([r["N"] for r in sel], [r["median_particle_steps_per_s"] for r in sel],
                    marker=marker, linestyle="-" if k == len(runs) - 1 else ":",
                    label=f"{phys} ({os.path.basename(os.path.normpath(folder))})")
    ax.axhline(4e9, color="grey", linewidth=0.8, linestyle="--")
    ax.text(1.1e6, 4.1e9, "goal at 4M (friction)", fontsize=8, color="grey")
    ax.set_xscale("log")
    ax.set_xlabel("spheres N")
    ax.set_ylabel("particle-steps / s (median of repetitions)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    ax.set_title("DEM step on one GPU, peer packing tiled")
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "throughput_vs_n.png"), dpi=120)

    fig, ax = plt.subplots(figsize=(8.4, 4.2))
    folder, rs, _ = runs[-1]
    sel = sorted((r for r in rs if r["physics"] == "friction" and "peak_device_arrays" in r),
                 key=lambda r: r["N"])
    labels = []
    for r in sel:
        for a in r["peak_device_arrays"]:
            if a["label"] not in labels and a["bytes_per_particle"] >= 16:
                labels.append(a["label"])
    bottom = [0.0] * len(sel)
    xs = list(range(len(sel)))
    for lab in labels + ["other"]:
        vals = []
        for r in sel:
            if lab == "other":
                vals.append(sum(a["bytes_per_particle"] for a in r["peak_device_arrays"]
                                if a["label"] not in labels))
            else:
                vals.append(sum(a["bytes_per_particle"] for a in r["peak_device_arrays"]
                                if a["label"] == lab))
        ax.bar(xs, vals, bottom=bottom, label=lab)
        bottom = [b + v for b, v in zip(bottom, vals)]
    ax.axhline(400, color="grey", linewidth=0.8, linestyle="--")
    ax.text(-0.4, 410, "goal: 400 B", fontsize=8, color="grey")
    ax.set_xticks(xs)
    ax.set_xticklabels([f"{r['N'] / 1e6:.3g}M" for r in sel])
    ax.set_xlabel("spheres N (friction)")
    ax.set_ylabel("device bytes per particle at the peak")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
    ax.set_title("Device memory by array, " + os.path.basename(os.path.normpath(folder)))
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "memory_vs_n.png"), dpi=120)


if __name__ == "__main__":
    main()
