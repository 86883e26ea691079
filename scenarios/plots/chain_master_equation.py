"""Charts of the chain_master_equation scene: Q heat maps, diag(Q) against band, and the
master-equation prediction against the full ensemble for the validation bands."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
PROCEDURES = ("nonlinear", "linear", "global", "global_trapped")
LABELS = {"nonlinear": "proc. 1", "linear": "proc. 2", "global": "global",
          "global_trapped": "global + trapped"}
with h5py.File(h5, "r") as f:
    B = int(f.attrs["bands"])
    runs = sorted((g for g in f if g.startswith("xi_")), key=lambda s: int(s[3:]))
    data = []
    for g in runs:
        d = f[g]
        v = d["validation"]
        h = d["held_out"]
        data.append(dict(xi=float(d.attrs["xi"]), Q1=d["Q_nonlinear"][:], Q2=d["Q_linear"][:],
                         Q3=d["Q_global"][:], Q4=d["Q_global_trapped"][:],
                         trapped=d["trapped_fraction"][:],
                         t=v["times"][:], sim=v["simulated"][:], p1=v["predicted_nonlinear"][:],
                         p2=v["predicted_linear"][:], p3=v["predicted_global"][:],
                         p4=v["predicted_global_trapped"][:],
                         b=(int(v.attrs["band_1"]), int(v.attrs["band_2"])),
                         th=h["times"][:],
                         held={k: h["rms_error_" + k][:] for k in PROCEDURES}))

for key, name in (("Q1", "nonlinear"), ("Q2", "linear"), ("Q3", "global"),
                  ("Q4", "global_trapped")):
    fig, axes = plt.subplots(1, len(data), figsize=(3.3 * len(data), 3.1), squeeze=False)
    for ax, d in zip(axes[0], data):
        q = d[key]
        off = q - np.diag(np.diag(q))
        im = ax.imshow(np.log10(np.maximum(off, 1e-7)), origin="lower", cmap="viridis")
        ax.set_title(f"xi = {d['xi']:g}: log10 Q_rs")
        ax.set_xlabel("source band s")
        ax.set_ylabel("band r")
        fig.colorbar(im, ax=ax, shrink=0.8)
    save(fig, outdir, f"Q_{name}.png")

fig, ax = plt.subplots(figsize=(4.8, 3.5))
for d in data:
    line, = ax.semilogy(range(B), -np.diag(d["Q1"]), "o-", ms=3, lw=0.9, label=f"xi = {d['xi']:g}")
    ax.semilogy(range(B), -np.diag(d["Q2"]), "x--", ms=3, lw=0.7, color=line.get_color())
    ax.semilogy(range(B), np.maximum(-np.diag(d["Q3"]), 1e-7), "s:", ms=2.5, lw=0.7,
                color=line.get_color())
ax.set_xlabel("band r (k = pi (r + 1/2) / B)")
ax.set_ylabel("-Q_rr (loss rate)")
ax.set_title("o procedure 1, x procedure 2, s global", fontsize=9)
ax.legend(fontsize=7)
save(fig, outdir, "Q_diagonal.png")

fig, axes = plt.subplots(1, len(data), figsize=(3.4 * len(data), 3.2), squeeze=False, sharey=True)
for ax, d in zip(axes[0], data):
    for b, c in zip(d["b"], ("C0", "C3")):
        ax.plot(d["t"], d["sim"][b], color=c, lw=1.4, label=f"band {b}: ensemble")
        ax.plot(d["t"], d["p1"][b], color=c, ls="--", lw=0.9, label="master eq. (proc. 1)")
        ax.plot(d["t"], d["p2"][b], color=c, ls=":", lw=0.9, label="master eq. (proc. 2)")
        ax.plot(d["t"], d["p3"][b], color=c, ls="-.", lw=0.8, label="global")
        ax.plot(d["t"], d["p4"][b], color="k" if c == "C0" else "C2", ls="-", lw=0.8,
                label="global + trapped")
    ax.set_title(f"xi = {d['xi']:g}")
    ax.set_xlabel("t")
axes[0][0].set_ylabel("<e_r> (normalized)")
axes[0][0].legend(fontsize=6)
save(fig, outdir, "prediction_vs_simulation.png")

# Held-out check: each procedure fitted on half of the realizations predicts the other half
# (every tone experiment); rms error over bands and experiments against time.
fig, axes = plt.subplots(1, len(data), figsize=(3.4 * len(data), 3.2), squeeze=False, sharey=True)
for ax, d in zip(axes[0], data):
    for k, p in enumerate(PROCEDURES):
        ax.semilogy(d["th"][1:], np.maximum(d["held"][p][1:], 1e-9), lw=1.0, color=f"C{k}",
                    label=LABELS[p])
    ax.set_title(f"xi = {d['xi']:g}")
    ax.set_xlabel("t")
axes[0][0].set_ylabel("rms error on held-out realizations")
axes[0][0].legend(fontsize=7)
save(fig, outdir, "held_out_error.png")

# Trapped fraction per band (weak localization), fitted with the global Q.
fig, ax = plt.subplots(figsize=(4.8, 3.4))
for d in data:
    ax.plot(range(B), d["trapped"], "o-", ms=3, lw=0.9, label=f"xi = {d['xi']:g}")
ax.set_xlabel("band r")
ax.set_ylabel("trapped fraction f_r")
ax.legend(fontsize=7)
save(fig, outdir, "trapped_fraction.png")
