"""Charts of the soft_collision scene: kinetic energy and the centre particle's overlap
against time, one panel per layout and material, one line per force model."""
import sys

import h5py

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    a = f.attrs["radius"]
    runs = f["runs"]
    layouts = sorted(runs, key=lambda lay: lay != "three")  # three in a row first
    panels = [(lay, mat) for lay in layouts for mat in runs[lay]]
    for quantity, ylabel, name in (
        ("kinetic_energy", "kinetic energy (uJ)", "kinetic_energy.png"),
        ("centre_overlap", "centre overlap / radius", "centre_overlap.png"),
    ):
        fig, axes = plt.subplots(1, len(panels), figsize=(3.4 * len(panels), 3.2), squeeze=False)
        for ax, (lay, mat) in zip(axes[0], panels):
            for model in runs[lay][mat]:
                g = runs[lay][mat][model]
                y = g[quantity][:]
                if quantity == "centre_overlap":
                    y = y / a
                ax.plot(g["time"][:] * 1e-3, y, lw=1.1, label=model)
            ax.set_title(f"{lay} spheres, {mat}")
            ax.set_xlabel("time (ms)")
            ax.set_ylabel(ylabel)
            ax.legend(fontsize=6)
        save(fig, outdir, name)
