"""Charts of the elastic_moduli scene: K*, G* against phi Z with EMT and FT predictions."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    t = {k: f["table"][k][:] for k in f["table"]}
x = t["phi"] * t["z_corrected"]
order = np.argsort(x)
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
for ax, m in zip(axes, ("K", "G")):
    ax.plot(x[order], t[m + "_star"][order], "ko", label="simulation")
    ax.plot(x[order], t[m + "_emt"][order], "-", label="EMT")
    ax.plot(x[order], t[m + "_ft1"][order], "--", label="FT, first ring")
    ax.plot(x[order], t[m + "_ft2"][order], "-.", label="FT, second ring")
    ax.plot(x[order], t[m + "_ft2_closure"][order], ":", label="FT, chi = 1/(phi Z)")
    ax.set_xlabel("phi Z")
    ax.set_ylabel(m + "* = " + m + " dbar / k_n")
    ax.legend(fontsize=7)
save(fig, outdir, "moduli_vs_phiZ.png")

fig, ax = plt.subplots(figsize=(5, 4))
ax.plot(t["phi"], t["z_corrected"], "o-", label="Z (non-rattlers)")
ax2 = ax.twinx()
ax2.plot(t["phi"], t["chi"], "s--", color="C1", label="chi")
ax.set_xlabel("phi")
ax.set_ylabel("Z")
ax2.set_ylabel("chi")
save(fig, outdir, "coordination_vs_phi.png")
