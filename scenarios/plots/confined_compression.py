"""Chart of the confined_compression scene: force on the top wall against strain, one line
per force model, with the measured experimental maximum where the scene gives one."""
import sys

import h5py

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    fig, ax = plt.subplots(figsize=(5.2, 3.8))
    for model in f["runs"]:
        g = f["runs"][model]
        note = f"{g.attrs['wall_seconds']:.1f} s"
        if "failure" in g.attrs:  # the model broke down: its curve ends there
            failure = str(g.attrs["failure"])
            how = "overlap limit" if failure.startswith("runaway overlap") else "diverged"
            note = f"{how} at {g['strain'][-1] * 100:.1f} %"
        ax.plot(g["strain"][:] * 100, g["top_wall_force"][:], lw=1.1, label=f"{model} ({note})")
    fx, sx = f.attrs["experiment_max_force"], f.attrs["experiment_strain"]
    if fx > 0:
        ax.plot([sx * 100], [fx], "k*", ms=10, label="experiment (maximum)")
    ax.set_xlabel("strain (%)")
    ax.set_ylabel("force on the top wall (N)")
    ax.legend(fontsize=7)
    save(fig, outdir, "force_vs_strain.png")
