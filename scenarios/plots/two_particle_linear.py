"""Charts of the two_particle_linear scene: overlap histories and measured vs closed form."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    fig, ax = plt.subplots(figsize=(6, 4))
    for name in sorted(f["collisions"], key=lambda s: int(s.split("_")[1])):
        g = f["collisions"][name]
        t, d = g["time"][:], g["overlap"][:]
        tc = g.attrs["contact_duration_closed_form"]
        inside = d > 0
        if not inside.any():
            continue
        t0 = t[inside][0]
        ax.plot((t - t0) / tc, d / d.max(), lw=1,
                label=f"m2/m1={g.attrs['mass_ratio']:.3g}, v={g.attrs['impact_speed']:.3g}")
    ax.set_xlim(-0.1, 1.2)
    ax.set_ylim(-0.1, 1.1)
    ax.axvline(1.0, color="k", ls=":", lw=0.8)
    ax.set_xlabel("time since contact / closed-form t_c")
    ax.set_ylabel("overlap / max overlap")
    ax.set_title("Linear spring-dashpot collisions")
    ax.legend(fontsize=6, ncol=2)
    save(fig, outdir, "overlap_histories.png")

    t = f["table"]
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, key, label in ((axes[0], "contact_duration", "contact duration"),
                           (axes[1], "restitution", "restitution")):
        meas, ref = t[key][:], t[key + "_closed_form"][:]
        rel = meas / ref - 1
        ax.scatter(np.arange(len(rel)), rel, c=np.log10(t["impact_speed"][:]), cmap="viridis")
        ax.axhline(0, color="k", lw=0.8)
        ax.axhspan(-1e-3, 1e-3, color="0.9", zorder=-1, label="1e-3 band")
        ax.set_xlabel("case (mass ratio x impact speed)")
        ax.set_ylabel(f"measured / closed form - 1")
        ax.set_title(label)
        ax.legend(fontsize=7)
    save(fig, outdir, "closed_form_comparison.png")
