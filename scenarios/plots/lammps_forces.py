"""Charts of the lammps_forces scene: the distribution of per-atom force and torque magnitudes
at each recorded step, and the pair pressure tensor and kinetic energy against the step."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    steps = sorted((int(k.split("_")[1]) for k in f if k.startswith("step_")))
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for s in steps:
        g = f[f"step_{s}"]
        for ax, key in ((axes[0], "force"), (axes[1], "torque")):
            mag = np.linalg.norm(g[key][:], axis=1)
            mag = mag[mag > 0]
            if mag.size:
                ax.hist(mag, bins=np.logspace(np.log10(mag.min()), np.log10(mag.max()), 30),
                        histtype="step", label=f"step {s}")
    for ax, key in ((axes[0], "|force| per atom"), (axes[1], "|torque| per atom")):
        ax.set_xscale("log")
        ax.set_xlabel(key + " (the data file's units)")
        ax.set_ylabel("atoms")
        ax.legend(fontsize=7)
    style = f.attrs["pair_style"]
    fig.suptitle(style.decode() if isinstance(style, bytes) else str(style), fontsize=7)
    save(fig, outdir, "force_distribution.png")

    if len(steps) > 1:
        fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
        p = np.array([f[f"step_{s}"]["pair_pressure_tensor"][:] for s in steps])
        for k, name in enumerate(["xx", "yy", "zz", "xy", "xz", "yz"]):
            axes[0].plot(steps, p[:, k], "o-", ms=3, label=f"P_{name}")
        axes[0].set_xlabel("step")
        axes[0].set_ylabel("pair pressure tensor")
        axes[0].legend(fontsize=7, ncol=2)
        ke = [f[f"step_{s}"].attrs["kinetic_energy"] for s in steps]
        axes[1].plot(steps, ke, "o-", ms=3)
        axes[1].set_xlabel("step")
        axes[1].set_ylabel("translational kinetic energy")
        save(fig, outdir, "pressure_and_energy.png")
