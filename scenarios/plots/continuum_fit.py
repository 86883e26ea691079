"""Charts of the continuum_fit scene: the element-test data against the fitted law (C*(phi),
fabric trace, K and G against F_v), DEM pressure against the law along the isotropic
preparation path, the DEM pure-shear path against the law, and the source's example path
with both volume-fraction updates."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]


def text(attr):
    """HDF5 string attributes come back as bytes or str depending on how they were stored."""
    return attr.decode() if isinstance(attr, bytes) else str(attr)


with h5py.File(h5, "r") as f:
    fits = {}
    for key in f["fit"]:
        g = f["fit"][key]
        fits[key] = {
            "name": text(g.attrs["data_set"]),
            **{"data_" + k: g["data"][k][:] for k in g["data"]},
            **{"prep_" + k: g["preparation"][k][:] for k in g["preparation"]},
            **{"law_" + k: g["law"][k][:] for k in g["law"]},
            **{"iso_" + k: g["isotropic"][k][:] for k in g["isotropic"]},
        }
    example = {k: {c: f["example"][k][c][:] for c in f["example"][k]} for k in f["example"]}
    shear = {k: f["shear"][k][:] for k in f["shear"]} if "shear" in f else None
    shear_fit = text(f["shear"].attrs["fit"]) if "shear" in f else None
    history = {k: f["history"][k][:] for k in f["history"]} if "history" in f else None
    history_fit = text(f["history"].attrs["fit"]) if "history" in f else None

studies = sorted({k.rsplit("_mu", 1)[0] for k in fits})
colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]

# Fits: one row per study, columns C*, F_v, K, G.
fig, axes = plt.subplots(len(studies), 4, figsize=(16, 3.6 * len(studies)), squeeze=False)
for row, study in enumerate(studies):
    keys = sorted(k for k in fits if k.rsplit("_mu", 1)[0] == study)
    for n, key in enumerate(keys):
        d, c = fits[key], colors[n % len(colors)]
        lab = d["name"]
        peak = int(d["prep_peak"][0])
        ax = axes[row][0]
        x, z = d["prep_phi"][peak:], d["prep_z"][peak:]
        ax.plot(x[::5], z[::5], ".", ms=2, color=c, alpha=0.4)
        ax.plot(d["law_nu"], d["law_C"], "-", color=c, label=lab)
        ax.set_xlabel("phi"), ax.set_ylabel("C* = Z*")
        ax = axes[row][1]
        ax.plot(d["data_phi"], d["data_fabric"], "o", color=c)
        ax.plot(d["law_nu"], d["law_Fv"], "-", color=c, label=lab)
        ax.set_xlabel("phi"), ax.set_ylabel("F_v = tr F")
        for col, m in ((2, "K"), (3, "G")):
            ax = axes[row][col]
            ax.plot(d["data_fabric"], d["data_" + m], "o", color=c)
            ax.plot(d["law_Fv"], d["law_" + m], "-", color=c, label=lab)
            ax.set_xlabel("F_v"), ax.set_ylabel(m + " (MPa)")
    axes[row][0].set_title(study + ": C*(phi), unloading series")
    axes[row][1].set_title("fabric trace, probed configurations")
    axes[row][2].set_title("bulk modulus")
    axes[row][3].set_title("shear modulus")
    axes[row][0].legend(fontsize=7)
save(fig, outdir, "fits.png")

# Isotropic path: DEM loading/unloading against the law's compression/decompression.
fig, axes = plt.subplots(len(studies), 2, figsize=(11, 4 * len(studies)), squeeze=False)
for row, study in enumerate(studies):
    keys = sorted(k for k in fits if k.rsplit("_mu", 1)[0] == study)
    for n, key in enumerate(keys):
        d, c = fits[key], colors[n % len(colors)]
        ax = axes[row][0]
        ax.plot(d["prep_phi"], d["prep_pressure"], "-", lw=0.8, color=c, alpha=0.5)
        ax.plot(d["iso_law_phi"], d["iso_law_p"], "--", color=c, label=d["name"] + " law")
        ax.plot(d["data_phi"], d["data_pressure"], "o", color=c, ms=4)
        ax = axes[row][1]
        for br, mk in (("loading", ":"), ("unloading", "-")):
            p, pl = d["iso_" + br + "_p_dem"], d["iso_" + br + "_p_law"]
            ok = p > 0.02 * p.max()
            ax.plot(d["iso_" + br + "_phi"][ok], (pl[ok] - p[ok]) / p[ok], mk, color=c,
                    label=d["name"] + " " + br)
    axes[row][0].set_xlabel("phi"), axes[row][0].set_ylabel("P (MPa)")
    axes[row][0].set_title(study + ": DEM (solid, dots: relaxed) vs law (dashed)")
    axes[row][0].legend(fontsize=7)
    axes[row][1].set_xlabel("phi"), axes[row][1].set_ylabel("(P_law - P_DEM) / P_DEM")
    axes[row][1].set_ylim(-1, 1), axes[row][1].axhline(0, color="k", lw=0.5)
    axes[row][1].set_title("relative error (where P_DEM > 2 % of its peak)")
    axes[row][1].legend(fontsize=6)
save(fig, outdir, "isotropic_validation.png")

if shear is not None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    e = shear["strain"]
    axes[0].plot(e, shear["dev_dem"], "o-", ms=3, label="DEM")
    axes[0].plot(e, shear["dev_law"], "-", label="law (" + shear_fit + ")")
    axes[0].set_xlabel("axial strain eps_xx (pure shear)"), axes[0].set_ylabel("sigma_xx - sigma_yy (MPa)")
    axes[0].legend()
    axes[1].plot(e, shear["p_dem"], "o-", ms=3, label="DEM")
    axes[1].plot(e, shear["p_law"], "-", label="law")
    axes[1].set_xlabel("axial strain eps_xx"), axes[1].set_ylabel("mean stress (MPa)")
    axes[1].legend()
    save(fig, outdir, "shear_validation.png")

fig, ax = plt.subplots(figsize=(6, 4))
for k, v in example.items():
    ax.plot(v["nu"], v["pressure"], label=k)
ax.set_xlabel("nu"), ax.set_ylabel("Cauchy pressure (source's units)")
ax.set_title("source's example: isotropic compression nu0 = 0.665 -> 0.82")
ax.legend()
save(fig, outdir, "spec_example.png")

if history is not None:
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(history["time"], history["pressure"], label="pressure")
    ax.plot(history["time"], history["deviatoric"], label="von Mises stress")
    ax.set_xlabel("time (table units)"), ax.set_ylabel("Cauchy stress (MPa)")
    ax.set_title("tabulated F history, law " + history_fit)
    ax.legend()
    save(fig, outdir, "history.png")
