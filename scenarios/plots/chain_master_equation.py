"""Charts of the chain_master_equation scene: Q heat maps, diag(Q) against band, and the
master-equation prediction against the full ensemble for the validation bands."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    B = int(f.attrs["bands"])
    runs = sorted((g for g in f if g.startswith("xi_")), key=lambda s: int(s[3:]))
    data = []
    for g in runs:
        d = f[g]
        v = d["validation"]
        data.append(dict(xi=float(d.attrs["xi"]), Q1=d["Q_nonlinear"][:], Q2=d["Q_linear"][:],
                         t=v["times"][:], sim=v["simulated"][:], p1=v["predicted_nonlinear"][:],
                         p2=v["predicted_linear"][:], b=(int(v.attrs["band_1"]), int(v.attrs["band_2"]))))

for key, name in (("Q1", "nonlinear"), ("Q2", "linear")):
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
ax.set_xlabel("band r (k = pi (r + 1/2) / B)")
ax.set_ylabel("-Q_rr (loss rate)")
ax.set_title("o procedure 1, x procedure 2")
ax.legend(fontsize=7)
save(fig, outdir, "Q_diagonal.png")

fig, axes = plt.subplots(1, len(data), figsize=(3.4 * len(data), 3.2), squeeze=False, sharey=True)
for ax, d in zip(axes[0], data):
    for b, c in zip(d["b"], ("C0", "C3")):
        ax.plot(d["t"], d["sim"][b], color=c, lw=1.4, label=f"band {b}: ensemble")
        ax.plot(d["t"], d["p1"][b], color=c, ls="--", lw=0.9, label="master eq. (proc. 1)")
        ax.plot(d["t"], d["p2"][b], color=c, ls=":", lw=0.9, label="master eq. (proc. 2)")
    ax.set_title(f"xi = {d['xi']:g}")
    ax.set_xlabel("t")
axes[0][0].set_ylabel("<e_r> (normalized)")
axes[0][0].legend(fontsize=6)
save(fig, outdir, "prediction_vs_simulation.png")
