"""Charts of the mixture_moduli scene: M against P per rubber fraction (log-log) with the
fitted power laws, M against the rubber fraction at each pressure, and the uniaxial M against
K + 4G/3. Also writes table.md (one row per configuration) next to the charts."""
import os
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    t = {k: f["table"][k][:] for k in f["table"]}
    fits = {k: f["fits"][k][:] for k in f["fits"]} if "fits" in f else {}

main = t["pair_rule_product_over_sum"] == t["pair_rule_product_over_sum"][0]
# Only probed states have moduli (states the servo did not converge to are not probed).
ok = main & ((t["probed"] > 0) if "probed" in t else (t["jammed"] > 0))
fractions = sorted(set(t["soft_fraction"][main]))
cmap = plt.get_cmap("viridis")
colour = {nu: cmap(i / max(1, len(fractions) - 1)) for i, nu in enumerate(fractions)}

# M against P per fraction, with the fits.
fig, ax = plt.subplots(figsize=(6.4, 4.8))
for nu in fractions:
    s = ok & (t["soft_fraction"] == nu)
    if not s.any():
        continue
    P, M = t["pressure"][s], t["M"][s]
    label = f"ν_r = {nu:g}"
    k = np.where(np.isclose(fits.get("soft_fraction", np.array([])), nu))[0]
    if k.size and np.isfinite(fits["M_exponent"][k[0]]):
        n, A = fits["M_exponent"][k[0]], fits["M_prefactor"][k[0]]
        se = fits["M_exponent_stderr"][k[0]]
        pp = np.geomspace(P.min(), P.max(), 50)
        ax.plot(pp, A * pp ** n, "-", color=colour[nu], lw=0.8)
        label += f": n = {n:.3f}" + (f" ± {se:.3f}" if np.isfinite(se) else "")
    ax.loglog(P, M, "o", color=colour[nu], label=label)
first = ok & (t["soft_fraction"] == fractions[0]) if fractions else ok
if first.any():  # the Hertzian slope through the stiffest mixture's highest-pressure point
    pp = np.geomspace(t["pressure"][ok].min(), t["pressure"][ok].max(), 10)
    k = np.argmax(t["pressure"][first])
    ref, p_ref = t["M"][first][k], t["pressure"][first][k]
    ax.loglog(pp, ref * (pp / p_ref) ** (1 / 3), "k:", lw=1, label="∝ P^(1/3)")
ax.set_xlabel("pressure P (MPa)")
ax.set_ylabel("P-wave modulus M (MPa, uniaxial probe)")
ax.legend(fontsize=7)
ax.set_title("M against P per rubber fraction, least-squares power laws")
save(fig, outdir, "M_vs_pressure.png")

# M against the rubber fraction at each target pressure.
fig, ax = plt.subplots(figsize=(6.4, 4.8))
targets = sorted(set(t["pressure_target"][ok]))
for i, p in enumerate(targets):
    s = ok & (t["pressure_target"] == p)
    order = np.argsort(t["soft_fraction"][s])
    ax.semilogy(t["soft_fraction"][s][order], t["M"][s][order], "o-",
                color=plt.get_cmap("plasma")(i / max(1, len(targets) - 1)), label=f"P = {p:g} MPa")
ax.set_xlabel("rubber volume fraction ν_r")
ax.set_ylabel("M (MPa)")
ax.legend(fontsize=7)
ax.set_title("M against rubber fraction at fixed pressure")
save(fig, outdir, "M_vs_rubber_fraction.png")

# Uniaxial M against K + 4G/3.
fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
for nu in fractions:
    s = ok & (t["soft_fraction"] == nu)
    axes[0].loglog(t["M_KG"][s], t["M"][s], "o", color=colour[nu], label=f"ν_r = {nu:g}")
    axes[1].semilogx(t["pressure"][s], t["M_over_M_KG"][s], "o-", color=colour[nu])
if ok.any():
    lim = [t["M_KG"][ok].min() * 0.8, t["M_KG"][ok].max() * 1.25]
    axes[0].plot(lim, lim, "k-", lw=0.8, label="M = K + 4G/3")
axes[0].set_xlabel("K + 4G/3 (MPa)")
axes[0].set_ylabel("M, uniaxial probe (MPa)")
axes[0].legend(fontsize=7)
axes[1].axhline(1, color="k", lw=0.8)
axes[1].set_xlabel("P (MPa)")
axes[1].set_ylabel("M / (K + 4G/3)")
save(fig, outdir, "M_vs_K_plus_4G_3.png")

# The load-bearing skeleton ([analysis] skeleton = true): the pressure carried by each contact
# type, contacts per particle by type, and the stiff network's largest cluster (filled: it wraps
# around the box along all three axes), against the rubber fraction, per target pressure.
if "skeleton_share_stiff_stiff" in t:
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    styles = ["-", "--", ":", "-."]
    for i, p in enumerate(sorted(set(t["pressure_target"][main]))):
        s = main & (t["pressure_target"] == p)
        order = np.argsort(t["soft_fraction"][s])
        nu = t["soft_fraction"][s][order]
        ls = styles[i % len(styles)]
        for key, label, c in [("share_stiff_stiff", "stiff–stiff", "C0"),
                              ("share_stiff_soft", "stiff–soft", "C1"),
                              ("share_soft_soft", "soft–soft", "C2")]:
            axes[0].plot(nu, t["skeleton_" + key][s][order], ls, marker="o", ms=3, color=c,
                         label=f"{label}, P = {p:g} MPa")
        for key, label, c in [("z_stiff_stiff", "stiff partners of a stiff bead", "C0"),
                              ("z_stiff_soft", "soft partners of a stiff bead", "C1"),
                              ("z_soft_stiff", "stiff partners of a soft bead", "C3"),
                              ("z_soft_soft", "soft partners of a soft bead", "C2")]:
            axes[1].plot(nu, t["skeleton_" + key][s][order], ls, marker="o", ms=3, color=c,
                         label=f"{label}, P = {p:g} MPa")
        # M over the glass packing's M at the same pressure, beside the shares.
        m0 = t["M"][s & (t["soft_fraction"] == 0) & ok]
        if m0.size and np.isfinite(m0[0]) and m0[0] > 0:
            keep = ok[s][order]
            axes[0].plot(nu[keep], t["M"][s][order][keep] / m0[0], ls, color="k", marker="s",
                         ms=3, label=f"M / M(ν_r = 0), P = {p:g} MPa")
        cl = t["skeleton_stiff_largest_cluster"][s][order]
        wraps = t["skeleton_stiff_wrapping_axes"][s][order]
        axes[2].plot(nu, cl, ls, color="k", lw=0.8, label=f"P = {p:g} MPa")
        axes[2].scatter(nu, cl, c=["k" if w == 3 else "white" for w in wraps], edgecolors="k", zorder=3)
    axes[1].axhline(4, color="k", lw=0.6, ls=":", label="d + 1 = 4: isostatic with friction")
    axes[0].set_ylabel("share of the pressure; M / M(ν_r = 0)")
    axes[1].set_ylabel("contacts per particle")
    axes[2].set_ylabel("largest stiff cluster / stiff beads")
    for ax in axes:
        ax.set_xlabel("rubber volume fraction ν_r")
        ax.legend(fontsize=6)
    axes[2].set_title("filled: wraps the periodic box along x, y and z", fontsize=8)
    save(fig, outdir, "skeleton_vs_rubber_fraction.png")

# The table, one row per configuration.
cols = [("soft_fraction", "ν_r", "{:.2f}"), ("pair_rule_product_over_sum", "rule", "{}"),
        ("pressure", "P (MPa)", "{:.4g}"), ("phi", "φ", "{:.4f}"), ("z_corrected", "Z̄", "{:.2f}"),
        ("rho_bulk", "ρ (kg/m³)", "{:.0f}"), ("K", "K (MPa)", "{:.4g}"), ("G", "G (MPa)", "{:.4g}"),
        ("M", "M (MPa)", "{:.4g}"), ("M_KG", "K+4G/3", "{:.4g}"),
        ("M_over_M_KG", "M/(K+4G/3)", "{:.4f}"), ("Vp", "V_p (m/s)", "{:.0f}"),
        ("M_other_rule_same_packing", "M other rule, same packing", "{:.4g}")]
lines = ["| " + " | ".join(c[1] for c in cols) + " |", "|" + "---|" * len(cols)]
for i in range(len(t["M"])):
    cells = []
    for key, _, fmt in cols:
        v = t[key][i]
        if key == "pair_rule_product_over_sum":
            cells.append("pq/(p+q)" if v > 0 else "harmonic")
        elif not np.isfinite(v):
            cells.append("—")
        else:
            cells.append(fmt.format(v))
    lines.append("| " + " | ".join(cells) + " |")
tmp = os.path.join(outdir, ".table.md.partial")
with open(tmp, "w") as out:
    out.write("\n".join(lines) + "\n")
os.replace(tmp, os.path.join(outdir, "table.md"))
