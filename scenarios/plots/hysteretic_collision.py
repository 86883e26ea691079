"""Charts of the hysteretic_collision scene: force against overlap, one loop per kc/k2."""
import sys

import h5py

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    k1, k2 = f.attrs["k1"], f.attrs["k2"]
    names = sorted(f["collisions"], key=lambda s: int(s.split("_")[1]))
    fig, axes = plt.subplots(1, len(names), figsize=(3.2 * len(names), 3.2), squeeze=False)
    for ax, name in zip(axes[0], names):
        g = f["collisions"][name]
        d, force = g["overlap"][:], g["normal_force"][:]
        inside = d > 0
        ax.plot(d[inside] * 1e3, force[inside], lw=1.2)
        dmax = d.max()
        ax.plot([0, dmax * 1e3], [0, k1 * dmax], "k:", lw=0.8, label="k1 (loading)")
        ax.axhline(0, color="0.6", lw=0.6)
        ax.set_title(f"kc/k2 = {g.attrs['kc_over_k2']:g}")
        ax.set_xlabel("overlap (um)")
        ax.set_ylabel("normal force (N)")
        ax.legend(fontsize=7)
    save(fig, outdir, "force_overlap_loops.png")
