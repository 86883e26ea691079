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
        a = {k: float(v) for k, v in d.attrs.items()}
        data.append(dict(xi=a["xi"], t=d["time"][:], te=d["te_mean"][:] / e0,
                         R=d["centre_mean"][:] - src, r2=d["width2_mean"][:],
                         source=d["source_energy"][:] / e0,
                         ratio=d["source_fraction_per_realization"][:],
                         end=int(a["analysis_end_sample"]), fit=a))

# 1. Energy profiles at four times, one panel per xi.
fig, axes = plt.subplots(1, len(data), figsize=(3.4 * len(data), 3.2), squeeze=False, sharey=True)
for ax, d in zip(axes[0], data):
    T = len(d["t"]) - 1
    # TE_p = b v^2/2 - F u/2 is not a positive local density: behind a front the beads sit
    # displaced (u far from 0) while F oscillates, so TE_p alternates in sign from bead to
    # bead. Averaged over blocks of 8 beads and drawn on a symmetric log axis (linear within
    # +-1e-6), negative blocks show as negative instead of being clipped.
    block = 8
    m = (n // block) * block
    x = (np.arange(m).reshape(-1, block).mean(axis=1)) - src
    for i in sorted({T // 8, T // 4, T // 2, T}):
        y = d["te"][i][:m].reshape(-1, block).mean(axis=1)
        ax.plot(x, y, lw=0.8, label=f"t = {d['t'][i]:g}")
    ax.set_yscale("symlog", linthresh=1e-6)
    ax.set_ylim(-1e-2, 1)
    ax.set_title(f"xi = {d['xi']:g}")
    ax.set_xlabel("bead p - source")
axes[0][0].set_ylabel("<TE_p> / E0, mean over 8 beads")
axes[0][0].legend(fontsize=7)
save(fig, outdir, "energy_profiles.png")

# 2. Near-source decay at the end of the analysis window (before the reflection): the first
# beads with their exponential fit, and the long range on log-log axes with a power law and
# an exponential fitted over the same beads.
fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.4))
for k, d in enumerate(data):
    c = f"C{k}"
    prof = d["te"][d["end"]]
    p = np.arange(0, min(80, n - src))
    a1.semilogy(p, np.maximum(prof[src + p], 1e-14), ".", ms=3, color=c,
                label=f"xi = {d['xi']:g}")
    f = d["fit"]
    pn = np.arange(0, int(f["near_beads"]))
    if np.isfinite(f["near_exponential_rate"]):
        a1.semilogy(pn, f["near_exponential_prefactor"] * np.exp(f["near_exponential_rate"] * pn),
                    "-", lw=0.8, color=c)
    q = np.arange(1, min(int(f["far_beads"]), n - 1 - src) + 1)
    a2.loglog(q, np.maximum(prof[src + q], 1e-14), ".", ms=2, color=c, label=f"xi = {d['xi']:g}")
    if d["xi"] > 0 and np.isfinite(f["far_power_law_exponent"]):
        a2.loglog(q, f["far_power_law_prefactor"] * q ** f["far_power_law_exponent"], "-",
                  lw=0.9, color=c)
        a2.loglog(q, f["far_exponential_prefactor"] * np.exp(f["far_exponential_rate"] * q),
                  ":", lw=0.9, color=c)
a1.set_xlabel("distance from the source (beads)")
a1.set_ylabel("<TE_p> / E0 at the window's end")
a1.set_title("near the source: exponential fit")
a1.set_ylim(bottom=1e-12)
a1.legend(fontsize=7)
a2.set_xlabel("distance from the source (beads)")
a2.set_title("long range: power law (—), exponential (···)", fontsize=10)
a2.set_ylim(bottom=1e-12)
save(fig, outdir, "near_source_decay.png")

# 3. Energy on the source bead against time (to the window's end), and its late-time value
# against xi, on log-log axes, both as a ratio of ensemble means and per realization.
fig, (a1, a2) = plt.subplots(1, 2, figsize=(8, 3.3))
xi, late, late_ratio = [], [], []
for k, d in enumerate(data):
    e = d["end"]
    a1.semilogy(d["t"][:e + 1], np.maximum(d["source"][:e + 1], 1e-12), lw=0.9, color=f"C{k}",
                label=f"xi = {d['xi']:g}")
    a1.semilogy(d["t"][:e + 1], np.maximum(d["ratio"][:e + 1], 1e-12), "--", lw=0.7,
                color=f"C{k}")
    tail = max(1, e // 10)
    if d["xi"] > 0:
        xi.append(d["xi"])
        late.append(np.mean(d["source"][e - tail + 1:e + 1]))
        late_ratio.append(np.mean(d["ratio"][e - tail + 1:e + 1]))
a1.set_xlabel("t")
a1.set_ylabel("source energy / E0")
a1.set_title("solid <TE>/<E0>, dashed <TE/E0>", fontsize=9)
a1.legend(fontsize=7)
if xi:
    a2.loglog(xi, late, "o-", label="<TE_source> / (v0^2/2)")
    a2.loglog(xi, late_ratio, "s--", label="<TE_source / (b_source v0^2/2)>")
    a2.legend(fontsize=7)
a2.set_xlabel("disorder xi")
a2.set_ylabel("residual source energy fraction")
save(fig, outdir, "source_residual.png")

# 4. Centre of energy and squared width.
fig, (a1, a2) = plt.subplots(1, 2, figsize=(8, 3.3))
for d in data:
    a1.plot(d["t"], d["R"], lw=0.9, label=f"xi = {d['xi']:g}")
    ok = d["t"] > 0
    a2.loglog(d["t"][ok], d["r2"][ok], lw=0.9, label=f"xi = {d['xi']:g}")
t = data[0]["t"][1:]
# Where the analysis window ends (0.95 of the front's arrival at the far end) and where the
# reflection starts: nothing after the first line enters the fitted exponents.
with h5py.File(h5, "r") as f:
    g = f[runs[0]]
    t_front = float(g.attrs["t_front_far_end"])
for ax in (a1, a2):
    ax.axvline(0.95 * t_front, color="0.5", ls="--", lw=0.7)
    if t_front <= t[-1]:
        ax.axvline(t_front, color="r", ls=":", lw=0.7)
a1.plot(t, np.sqrt(1.5) * t, "k:", lw=0.8, label="sqrt(3/2) t")
a2.loglog(t, data[0]["r2"][-1] * (t / t[-1]) ** 2, "k:", lw=0.8, label="~ t^2 (ballistic)")
a1.set_xlabel("t")
fig.suptitle("dashed: end of the analysis window; red dotted: front reaches the far end",
             fontsize=9)
a1.set_ylabel("<R> - source")
a2.set_xlabel("t")
a2.set_ylabel("<r^2>")
a1.legend(fontsize=7)
a2.legend(fontsize=7)
save(fig, outdir, "spreading.png")
