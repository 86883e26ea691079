"""Charts of the chain_impulse scene: energy profiles (twin peaks), near-source decay,
energy left on the source bead, centre of energy and squared width against time."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    src, e0, n = int(f.attrs["source"]), float(f.attrs["energy0"]), int(f.attrs["beads"])
    runs = sorted((g for g in f if g.startswith("xi_")), key=lambda s: int(s[3:]))
    data = []
    for g in runs:
        d = f[g]
        data.append(dict(xi=float(d.attrs["xi"]), t=d["time"][:], te=d["te_mean"][:] / e0,
                         R=d["centre_mean"][:] - src, r2=d["width2_mean"][:],
                         source=d["source_energy"][:] / e0))

# 1. Energy profiles at four times, one panel per xi.
fig, axes = plt.subplots(1, len(data), figsize=(3.4 * len(data), 3.2), squeeze=False, sharey=True)
for ax, d in zip(axes[0], data):
    T = len(d["t"]) - 1
    for i in sorted({T // 8, T // 4, T // 2, T}):
        ax.semilogy(np.arange(n) - src, np.maximum(d["te"][i], 1e-12), lw=0.8,
                    label=f"t = {d['t'][i]:g}")
    ax.set_ylim(1e-8, 1)
    ax.set_title(f"xi = {d['xi']:g}")
    ax.set_xlabel("bead p - source")
axes[0][0].set_ylabel("<TE_p> / E0")
axes[0][0].legend(fontsize=7)
save(fig, outdir, "energy_profiles.png")

# 2. Near-source decay at the last time.
fig, ax = plt.subplots(figsize=(4.5, 3.4))
for d in data:
    p = np.arange(0, min(80, n - src))
    ax.semilogy(p, np.maximum(d["te"][-1][src + p], 1e-14), marker=".", ms=3, lw=0.8,
                label=f"xi = {d['xi']:g}")
ax.set_xlabel("distance from the source (beads)")
ax.set_ylabel("<TE_p>(t_max) / E0")
ax.set_title("near-source (localized) energy")
ax.legend(fontsize=7)
save(fig, outdir, "near_source_decay.png")

# 3. Energy on the source bead against time, and its late-time value against xi.
fig, (a1, a2) = plt.subplots(1, 2, figsize=(8, 3.3))
for d in data:
    a1.semilogy(d["t"], np.maximum(d["source"], 1e-12), lw=0.9, label=f"xi = {d['xi']:g}")
a1.set_xlabel("t")
a1.set_ylabel("<TE_source> / E0")
a1.legend(fontsize=7)
xi = [d["xi"] for d in data]
late = [np.mean(d["source"][-max(1, len(d["source"]) // 10):]) for d in data]
a2.plot(xi, late, "o-")
a2.set_xlabel("disorder xi")
a2.set_ylabel("residual source energy / E0")
save(fig, outdir, "source_residual.png")

# 4. Centre of energy and squared width.
fig, (a1, a2) = plt.subplots(1, 2, figsize=(8, 3.3))
for d in data:
    a1.plot(d["t"], d["R"], lw=0.9, label=f"xi = {d['xi']:g}")
    ok = d["t"] > 0
    a2.loglog(d["t"][ok], d["r2"][ok], lw=0.9, label=f"xi = {d['xi']:g}")
t = data[0]["t"][1:]
a1.plot(t, np.sqrt(1.5) * t, "k:", lw=0.8, label="sqrt(3/2) t")
a2.loglog(t, data[0]["r2"][-1] * (t / t[-1]) ** 2, "k:", lw=0.8, label="~ t^2 (ballistic)")
a1.set_xlabel("t")
a1.set_ylabel("<R> - source")
a2.set_xlabel("t")
a2.set_ylabel("<r^2>")
a1.legend(fontsize=7)
a2.legend(fontsize=7)
save(fig, outdir, "spreading.png")
