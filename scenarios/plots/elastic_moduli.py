"""Charts of the elastic_moduli scene: K*, G* against phi Z with EMT and FT predictions
(one panel row per preparation friction / probing stiffness ratio), Z and chi against phi,
moduli against probe amplitude (amplitude sweeps), and the moduli scatter against N."""
import json
import os
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    t = {k: f["table"][k][:] for k in f["table"]}
    sweeps = {}
    if "sweep" in f:
        for name in f["sweep"]:
            sweeps[name] = {k: f["sweep"][name][k][:] for k in f["sweep"][name]}


def groups(t):
    """Rows with the same preparation friction, stiffness ratio and size form one series."""
    keys = np.stack([np.nan_to_num(t["mu_preparation"], nan=-1), t["kt_kn"], t["particles"]], 1)
    out = {}
    for i, k in enumerate(map(tuple, keys)):
        out.setdefault(k, []).append(i)
    return out


series = groups(t)


def study_title():
    """Contact law, N and branch from the run's summary.json (beside results.h5)."""
    path = os.path.join(os.path.dirname(os.path.abspath(h5)), "summary.json")
    try:
        with open(path) as f:
            par = json.load(f).get("parameters", {})
    except (OSError, ValueError):
        return None
    law = par.get("contact.normal", "linear")
    counts = par.get("ensemble.counts") or []
    n = ", ".join(str(v) for v in counts) if counts else par.get("particles.count", "?")
    branch = par.get("preparation.branch", "unloading")
    return "%s contacts, N = %s, %s branch" % (law, n, branch)


title = study_title()
# Outputs written before the "jammed" column marked unjammed states by Z = 0.
jammed = t["jammed"] > 0 if "jammed" in t else t["z_corrected"] > 0


def label_of(key):
    """Legend text of a series: only the parameters that vary between series."""
    label = []
    if key[0] >= 0:
        label.append("mu %g" % key[0])
    if len({k[1] for k in series}) > 1:
        label.append("kt/kn %g" % key[1])
    if len({k[2] for k in series}) > 1:
        label.append("N %d" % key[2])
    return ", ".join(label) or "simulation"


# EMT depends on phi Z (and k_t/k_n) only: one curve through every jammed row of a
# stiffness ratio. FT differs per configuration: markers, not lines zig-zagging between
# scattered seeds.
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
for ax, m in zip(axes, ("K", "G")):
    for n, (key, idx) in enumerate(sorted(series.items())):
        idx = np.array(idx)
        idx = idx[jammed[idx]]  # unjammed configurations have no moduli
        if len(idx) == 0:
            continue
        x = t["phi"][idx] * t["z_corrected"][idx]
        c = "C%d" % n
        ax.plot(x, t[m + "_star"][idx], "o", color=c, label=label_of(key))
        ax.plot(x, t[m + "_ft2"][idx], "x", color=c, ms=5,
                label="FT, second ring (measured chi)" if n == 0 else None)
    ratios = sorted(set(t["kt_kn"][jammed]))
    for j, r in enumerate(ratios):
        sel = np.where(jammed & (t["kt_kn"] == r))[0]
        x = t["phi"][sel] * t["z_corrected"][sel]
        o = np.argsort(x)
        tag = " (kt/kn %g)" % r if len(ratios) > 1 else ""
        ls = ["-", "--", ":", "-."][j % 4]
        ax.plot(x[o], t[m + "_emt"][sel][o], ls, color="k", lw=0.9, label="EMT" + tag)
        # The closure's FT also reads phi and Z apart, so it scatters a little about a
        # curve: markers, like the measured-chi FT.
        ax.plot(x[o], t[m + "_ft2_closure"][sel][o], "+", color="0.45", ms=5,
                label="FT, chi = 1/(phi Z)" + tag)
    ax.set_xlabel("phi Z")
    ax.set_ylabel(m + "* = " + m + " dbar / k_n")
    ax.legend(fontsize=7)
if title:
    fig.suptitle(title, fontsize=10)
save(fig, outdir, "moduli_vs_phiZ.png")

# Unjammed states carry no contact network: open markers at Z = 0, never joined by lines.
fig, axes = plt.subplots(1, 3, figsize=(14, 4))
for n, (key, idx) in enumerate(sorted(series.items())):
    idx = np.array(idx)
    o = idx[np.argsort(t["phi"][idx])]
    jam, loose = o[jammed[o]], o[~jammed[o]]
    c = "C%d" % n
    axes[0].plot(t["phi"][jam], t["z_corrected"][jam], "o-", color=c, label=label_of(key))
    axes[1].plot(t["phi"][jam], t["chi"][jam], "s-", color=c, label=label_of(key))
    if len(loose):
        axes[0].plot(t["phi"][loose], np.zeros(len(loose)), "o", mfc="none", color=c,
                     label="unjammed" if n == 0 else None)
    x = t["phi"][jam] * t["z_corrected"][jam]
    axes[2].plot(x, t["chi"][jam], "s", color=c, label=label_of(key))
xs = t["phi"][jammed] * t["z_corrected"][jammed]
if len(xs):
    grid = np.linspace(xs.min(), xs.max(), 100)
    axes[2].plot(grid, 1 / grid, "k:", lw=0.9, label="closure chi = 1/(phi Z)")
axes[0].set_ylabel("Z (non-rattlers)")
axes[1].set_ylabel("chi = <(Z - Zbar)^2> / Zbar^2")
axes[2].set_ylabel("chi")
axes[2].set_xlabel("phi Z")
for ax in axes[:2]:
    ax.set_xlabel("phi")
for ax in axes:
    ax.legend(fontsize=7)
if title:
    fig.suptitle(title, fontsize=10)
save(fig, outdir, "coordination_vs_phi.png")

# The per-configuration table as markdown, for reading without HDF5 tools.
columns = [("phi", "phi", "%.4f"), ("z_corrected", "Z", "%.3f"), ("chi", "chi", "%.4f"),
           ("rho", "rho", "%.3f"), ("zeta", "zeta", "%.3f"), ("pressure_star", "P*", "%.3e"),
           ("K_star", "K*", "%.4f"), ("G_star", "G*", "%.4f"), ("K_emt", "K* EMT", "%.4f"),
           ("G_emt", "G* EMT", "%.4f"), ("K_ft2", "K* FT2", "%.4f"), ("G_ft2", "G* FT2", "%.4f"),
           ("M_over_K_plus_4G_3", "M/(K+4G/3)", "%.4f")]
columns = [c for c in columns if c[0] in t]
lines = ["| series | " + " | ".join(c[1] for c in columns) + " |",
         "|---" * (len(columns) + 1) + "|"]
for key, idx in sorted(series.items()):
    for i in sorted(idx, key=lambda i: -t["phi"][i]):
        cells = [c[2] % t[c[0]][i] for c in columns]
        if not jammed[i]:
            cells = cells[:2] + ["unjammed"] * (len(cells) - 2)
        lines.append("| %s | " % label_of(key) + " | ".join(cells) + " |")
tmp = outdir + "/.table.md.partial"
with open(tmp, "w") as f:
    f.write("\n".join(lines) + "\n")
os.replace(tmp, outdir + "/table.md")

if sweeps:
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for n, (name, s) in enumerate(sorted(sweeps.items())):
        c = "C%d" % n
        for m, mk in (("K", "o-"), ("G", "s--"), ("M", "^:")):
            axes[0].loglog(s["amplitude"], np.abs(s[m + "_star"]), mk, color=c, ms=4,
                           label="%s* %s" % (m, name))
        axes[1].loglog(s["amplitude"], s["eta_K"], "o-", color=c, ms=4, label="eta, " + name)
        if "reversal_residual" in s:
            axes[1].loglog(s["amplitude"], np.abs(s["reversal_residual"]), "x--", color=c,
                           ms=5, label="|reversal residual|, " + name)
    axes[0].set_xlabel("probe strain amplitude")
    axes[0].set_ylabel("secant modulus (dimensionless)")
    axes[0].legend(fontsize=6)
    axes[1].set_xlabel("probe strain amplitude")
    axes[1].set_ylabel("isotropic probe: eta, |reversal residual|")
    axes[1].legend(fontsize=6)
    save(fig, outdir, "moduli_vs_amplitude.png")

sizes = np.unique(t["particles"])
if len(sizes) > 1 and "phi_target" in t:
    fig, ax = plt.subplots(figsize=(5, 4))
    for n, target in enumerate(np.unique(t["phi_target"])):
        sel = t["phi_target"] == target
        for m, mk in (("K", "o-"), ("G", "s--")):
            rel = []
            for N in sizes:
                v = t[m + "_star"][sel & (t["particles"] == N)]
                rel.append(np.std(v, ddof=1) / np.mean(v) if len(v) > 1 else np.nan)
            ax.loglog(sizes, rel, mk, color="C%d" % n, label="%s*, phi %.3f" % (m, target))
    ax.loglog(sizes, 0.1 * (sizes / sizes[0]) ** -0.5, "k:", lw=0.8, label="N^-1/2")
    ax.set_xlabel("N")
    ax.set_ylabel("relative scatter over seeds (std / mean)")
    ax.legend(fontsize=7)
    save(fig, outdir, "scatter_vs_size.png")
