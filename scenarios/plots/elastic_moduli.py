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
    prep = {k: f["preparation"][k][:] for k in f["preparation"]} if "preparation" in f else {}
    reversibility = {}
    if "reversibility" in f:
        for name in f["reversibility"]:
            g = f["reversibility"][name]
            reversibility[name] = {k: g[k][:] for k in g}
    sweeps = {}
    if "sweep" in f:
        for name in f["sweep"]:
            sweeps[name] = {k: f["sweep"][name][k][:] for k in f["sweep"][name]}


def groups(t):
    """Rows with the same preparation friction, stiffness ratio and size form one series."""
    kc = t["kc_preparation"] if "kc_preparation" in t else np.zeros_like(t["kt_kn"])
    keys = np.stack([np.nan_to_num(t["mu_preparation"], nan=-1), t["kt_kn"], t["particles"], kc],
                    1)
    out = {}
    for i, k in enumerate(map(tuple, keys)):
        out.setdefault(k, []).append(i)
    return out


series = groups(t)


def summary_json():
    path = os.path.join(os.path.dirname(os.path.abspath(h5)), "summary.json")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def study_parameters():
    """The parameters of the run's summary.json (beside results.h5), {} if absent."""
    path = os.path.join(os.path.dirname(os.path.abspath(h5)), "summary.json")
    try:
        with open(path) as f:
            return json.load(f).get("parameters", {})
    except (OSError, ValueError):
        return {}


def study_title():
    """Contact law, N and branch from the run's summary.json."""
    par = study_parameters()
    if not par:
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
    if len({k[3] for k in series}) > 1:
        label.append("kc %g" % key[3])
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

def compact_legend(ax, names, styles):
    """One legend entry per series (its colour) and one per quantity (marker and line style),
    instead of one per drawn line: studies with many configurations stay readable."""
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color="C%d" % n, lw=2, label=name) for n, name in enumerate(names)]
    handles += [Line2D([], [], color="k", marker=mk[0], ls=mk[1:], ms=4, label=label)
                for mk, label in styles]
    ax.legend(handles=handles, fontsize=6, ncol=2 if len(handles) > 10 else 1)


if sweeps:
    fabric = all("fabric_dev_change_G" in sw for sw in sweeps.values())
    names = sorted(sweeps)
    fig, axes = plt.subplots(1, 3 if fabric else 2, figsize=(15 if fabric else 10, 4))
    for n, (name, s) in enumerate(sorted(sweeps.items())):
        c = "C%d" % n
        for m, mk in (("K", "o-"), ("G", "s--"), ("M", "^:")):
            axes[0].loglog(s["amplitude"], np.abs(s[m + "_star"]), mk, color=c, ms=4)
        axes[1].loglog(s["amplitude"], s["eta_K"], "o-", color=c, ms=4)
        if "reversal_residual" in s:
            axes[1].loglog(s["amplitude"], np.abs(s["reversal_residual"]), "x--", color=c,
                           ms=5)
    axes[0].set_xlabel("probe strain amplitude")
    axes[0].set_ylabel("secant modulus (dimensionless)")
    compact_legend(axes[0], names, (("o-", "K*"), ("s--", "G*"), ("^:", "M*")))
    axes[1].set_xlabel("probe strain amplitude")
    axes[1].set_ylabel("isotropic probe: eta, |reversal residual|")
    compact_legend(axes[1], names, (("o-", "eta"), ("x--", "|reversal residual|")))
    if fabric:  # how the contact network changes along the probe
        for n, (name, sw) in enumerate(sorted(sweeps.items())):
            c = "C%d" % n
            for key, mk, what in (("fabric_v_change_K", "o-", "dF_v/F_v isotropic"),
                                  ("fabric_v_change_G", "s--", "dF_v/F_v shear"),
                                  ("fabric_dev_change_G", "^:", "d(F_xx-F_yy)/F_v shear")):
                y = np.abs(sw[key])
                ok = y > 0
                axes[2].loglog(sw["amplitude"][ok], y[ok], mk, color=c, ms=4)
        axes[2].set_xlabel("probe strain amplitude")
        axes[2].set_ylabel("|fabric change along the probe| / F_v")
        compact_legend(axes[2], names, (("o-", "dF_v/F_v isotropic"), ("s--", "dF_v/F_v shear"),
                                        ("^:", "d(F_xx-F_yy)/F_v shear")))
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

# Probing tangential stiffness (probe.kt_over_kn lists): the gain of K* and G* over the
# frictionless probe of the same configuration against k_t/k_n, and G split into its normal
# and tangential contact parts against phi Z, each with the fluctuation theory's partition:
# G_N^FT = (3/5) K^FT (K^FT has no tangential part), G_T^FT = G^FT - G_N^FT, linear in k_t/k_n.
ratios = sorted(set(t["kt_kn"][jammed]))
if len(ratios) > 2 and 0.0 in ratios:
    cfg = np.round(t["phi"], 6) * 1e6 + np.nan_to_num(t["mu_preparation"], nan=-1) * 1e3 + t["seed"]
    base = {c: i for i, c in enumerate(cfg) if t["kt_kn"][i] == 0 and jammed[i]}
    phiz = t["phi"] * t["z_corrected"]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    configs = sorted(base, key=lambda c: phiz[base[c]])
    near = min(configs, key=lambda c: abs(phiz[base[c]] - 4.5))
    picks = [near] + [c for c in (configs[0], configs[-1]) if c != near]
    for n, c in enumerate(picks):
        rows = np.array([i for i in range(len(cfg)) if cfg[i] == c and jammed[i]])
        rows = rows[np.argsort(t["kt_kn"][rows])]
        b = base[c]
        r = t["kt_kn"][rows]
        lab = "phi Z = %.2f" % phiz[b]
        axes[0].plot(r, t["K_star"][rows] - t["K_star"][b], "s-", color="C%d" % n, ms=4,
                     label="dK*, " + lab)
        axes[0].plot(r, t["G_star"][rows] - t["G_star"][b], "o-", color="C%d" % n, ms=4,
                     mfc="none", label="dG*, " + lab)
        axes[0].plot(r, t["G_ft2"][rows] - t["G_ft2"][b], ":", color="C%d" % n, lw=1,
                     label="dG FT2" if n == 0 else None)
    axes[0].axhline(0, color="k", lw=0.6)
    axes[0].set_xlabel("k_t / k_n of the probe")
    axes[0].set_ylabel("gain over k_t = 0 (same configuration)")
    axes[0].set_title("tangential stiffness: dK*, dG* (FT: dK = 0)", fontsize=9)
    axes[0].legend(fontsize=6)
    for n, r in enumerate(ratios):
        sel = np.where(jammed & (t["kt_kn"] == r))[0]
        sel = sel[np.argsort(phiz[sel])]
        gn_ft = 0.6 * t["K_ft2"][sel]
        axes[1].plot(phiz[sel], t["G_n_star"][sel], "o", color="C%d" % n, ms=4,
                     label="kt/kn %g" % r)
        if r == 0:  # G_N^FT does not depend on k_t/k_n
            axes[1].plot(phiz[sel], gn_ft, "-", color="k", lw=0.8, label="FT2, any kt/kn")
        if r > 0:
            axes[2].plot(phiz[sel], t["G_t_star"][sel], "o", color="C%d" % n, ms=4,
                         label="kt/kn %g" % r)
            axes[2].plot(phiz[sel], t["G_ft2"][sel] - gn_ft, "-", color="C%d" % n, lw=0.8)
    for ax, name in ((axes[1], "G_N* (normal contact forces)"),
                     (axes[2], "G_T* (tangential contact forces)")):
        ax.set_xlabel("phi Z")
        ax.set_ylabel(name)
        ax.set_title(name.split(" ")[0] + ": markers measured, lines FT2 partition", fontsize=9)
        ax.legend(fontsize=6)
    if title:
        fig.suptitle(title, fontsize=10)
    save(fig, outdir, "tangential_stiffness.png")

# The tangential share of the shear modulus, G_T*/G_N*, against phi Z per series and (with
# several probing ratios) against k_t/k_n: affine 1.5 k_t/k_n, FT2's partition
# (G^FT - (3/5) K^FT) / ((3/5) K^FT), and the source's Hertz value 0.15 for orientation.
share_rows = jammed & (t["kt_kn"] > 0) & (t["G_n_star"] > 0) if "G_n_star" in t else []
if np.any(share_rows):
    phiz = t["phi"] * t["z_corrected"]
    share = np.where(share_rows, t["G_t_star"] / np.where(share_rows, t["G_n_star"], 1), np.nan)
    share_ft = (t["G_ft2"] - 0.6 * t["K_ft2"]) / (0.6 * t["K_ft2"])
    several = len(set(t["kt_kn"][share_rows])) > 2
    fig, axes = plt.subplots(1, 2 if several else 1, figsize=(10 if several else 5.5, 4),
                             squeeze=False)
    axes = axes[0]
    for n, (key, rows) in enumerate(sorted(series.items())):
        rows = np.array([i for i in rows if share_rows[i]])
        if not len(rows):
            continue
        rows = rows[np.argsort(phiz[rows])]
        c = "C%d" % (n % 10)
        lab = "kt/kn %g" % key[1] if several else ("mu %g" % key[0] if key[0] >= 0 else "series")
        axes[0].plot(phiz[rows], share[rows], "o", color=c, ms=4, label=lab)
        axes[0].plot(phiz[rows], share_ft[rows], "-", color=c, lw=0.8)
        axes[0].axhline(1.5 * key[1], color=c, ls="--", lw=0.6)
    axes[0].axhline(0.15, color="k", ls=":", lw=1, label="source, Hertz: 0.15")
    axes[0].set_yscale("log")
    axes[0].set_xlabel("phi Z")
    axes[0].set_ylabel("G_T* / G_N*")
    axes[0].set_title("markers measured, lines FT2 partition, dashed affine 1.5 kt/kn",
                      fontsize=8)
    axes[0].legend(fontsize=6)
    if several:
        cfg = np.round(t["phi"], 6)
        for n, c in enumerate(sorted(set(cfg[share_rows]))):
            rows = np.where(share_rows & (cfg == c))[0]
            rows = rows[np.argsort(t["kt_kn"][rows])]
            axes[1].loglog(t["kt_kn"][rows], share[rows], "o-", color="C%d" % (n % 10), ms=4,
                           label="phi Z = %.2f" % np.mean(phiz[rows]))
        r = np.array(sorted(set(t["kt_kn"][share_rows])))
        axes[1].loglog(r, 1.5 * r, "k--", lw=0.8, label="affine 1.5 kt/kn")
        axes[1].axhline(0.15, color="k", ls=":", lw=1, label="source, Hertz: 0.15")
        axes[1].set_xlabel("k_t / k_n of the probe")
        axes[1].set_ylabel("G_T* / G_N*")
        axes[1].legend(fontsize=6)
    if title:
        fig.suptitle(title, fontsize=10)
    save(fig, outdir, "shear_partition.png")

# The preparation path (series recorded along the protocol, written since the series carry
# a direction): contact-number fractions, Z, P*, E_kin/E_pot and the inertial number against
# phi, compression solid and decompression dashed, one colour per preparation variant.
if "direction" in prep and len(prep["phi"]):
    mus = study_parameters().get("preparation.mu") or []
    variants = sorted(set(prep["variant"].astype(int)))
    # Variant names as the run tagged them (summary.json "jamming"), else by friction.
    tags = {j["variant"]: j.get("tag") for j in summary_json().get("jamming", [])}

    def vlabel(v):
        if tags.get(v):
            return tags[v]
        return "mu %g" % mus[v] if len(mus) == len(variants) else "variant %d" % v

    hertz = np.all(np.isnan(prep["pressure_star"]))
    fig, axes = plt.subplots(2, 3, figsize=(14, 7.5))
    panels = [(axes[0, 0], "z_corrected", "Z (non-rattlers)", False),
              (axes[0, 1], "pressure" if hertz else "pressure_star",
               "P" if hertz else "P* = P dbar / k_n", "symlog"),
              (axes[0, 2], "ekin_over_epot", "E_kin / E_pot", True),
              (axes[1, 0], "inertial_number", "I_v = rate dbar sqrt(rho / P)", True)]
    for n, v in enumerate(variants):
        on = prep["variant"].astype(int) == v
        for ax, key, name, log in panels:
            for d, ls in ((1, "-"), (-1, "--")):
                sel = on & (prep["direction"] == d)
                y = prep[key][sel]
                ok = np.isfinite(y) & ((y > 0) if log is True else True)
                ax.plot(prep["phi"][sel][ok], y[ok], ls, color="C%d" % n, lw=1,
                        label=vlabel(v) + (" compression" if d > 0 else " decompression"))
            ax.set_ylabel(name)
            if log is True:
                ax.set_yscale("log")
            elif log == "symlog":  # cohesive packings go tensile on decompression
                ax.set_yscale("symlog", linthresh=1e-6)
    # Contact-number fractions of the first and the last variant.
    for ax, v in ((axes[1, 1], variants[0]), (axes[1, 2], variants[-1])):
        on = prep["variant"].astype(int) == v
        for k in range(7):
            key = "contact_fraction_%d" % k if k < 6 else "contact_fraction_6_or_more"
            for d, ls in ((1, "-"), (-1, "--")):
                sel = on & (prep["direction"] == d)
                ax.plot(prep["phi"][sel], prep[key][sel], ls, color=plt.cm.viridis(k / 6), lw=1,
                        label=("%d contacts" % k if k < 6 else ">= 6 contacts") if d > 0 else None)
        ax.set_ylabel("fraction of particles")
        ax.set_title(vlabel(v) + " (solid: compression, dashed: decompression)", fontsize=8)
        ax.legend(fontsize=6, ncol=2)
    for ax in axes.flat:
        ax.set_xlabel("phi")
    axes[0, 0].legend(fontsize=6)
    if title:
        fig.suptitle(title + ": preparation path", fontsize=10)
    save(fig, outdir, "preparation_path.png")

# Jamming density against the preparation friction (summary.json "jamming"): the fitted root
# of the unloading branch with its standard error, and the lowest density of the branch with
# a contact network and the highest without (the range where the network flickers).
jam = [j for j in summary_json().get("jamming", []) if j.get("mu_preparation") is not None]
if len({j["mu_preparation"] for j in jam}) > 1:
    mu = np.array([j["mu_preparation"] for j in jam], float)
    val = lambda k: np.array([np.nan if j.get(k) is None else j[k] for j in jam], float)
    fig, ax = plt.subplots(figsize=(6, 4))
    # Only the series that have a value are drawn: a branch that stays jammed down to its
    # lowest target has no fitted root and no unjammed state, and the chart says so instead
    # of listing empty series.
    phi_j = val("phi_J")
    if np.isfinite(phi_j).any():
        ax.errorbar(mu, phi_j, yerr=np.nan_to_num(val("phi_J_stderr")), fmt="o-", color="C0",
                    capsize=3, label="phi_J (fit of the unloading branch)")
    missing = []
    for key, mk, c, lab in (("phi_lowest_jammed", "v", "C1", "lowest phi with a network (unloading)"),
                            ("phi_highest_unjammed", "^", "C2", "highest phi without one")):
        y = val(key)
        if np.isfinite(y).any():
            ax.plot(mu, y, mk, color=c, label=lab)
    if not np.isfinite(phi_j).all():
        missing.append("no phi_J for mu = %s (fewer than 4 unloading samples\nwith 0 < P <= "
                       "preparation.jamming_fit_pressure_max)" % ", ".join(
                           "%g" % m for m, p in zip(mu, phi_j) if not np.isfinite(p)))
    unj = val("phi_highest_unjammed")
    if not np.isfinite(unj).all():
        missing.append("no unjammed state for mu = %s\n(a network down to the lowest target)" %
                       ", ".join("%g" % m for m, p in zip(mu, unj) if not np.isfinite(p)))
    ax.set_xscale("symlog", linthresh=0.01)
    # The notes go under the axis label, where no point can hide them.
    ax.set_xlabel("\n".join(["preparation friction mu"] + missing))
    fig.set_size_inches(6, 4 + 0.3 * sum(m.count("\n") + 1 for m in missing))
    # Densities equal to a few digits (a branch stopped at its lowest target) get a readable
    # range instead of an offset axis of 1e-7.
    ax.ticklabel_format(axis="y", useOffset=False)
    lo, hi = ax.get_ylim()
    if hi - lo < 0.02:
        ax.set_ylim(0.5 * (lo + hi) - 0.01, 0.5 * (lo + hi) + 0.01)
    ax.set_ylabel("jamming volume fraction")
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title, fontsize=9)
    save(fig, outdir, "jamming_vs_friction.png")

# Cohesion list (preparation.kc): K* and G* against k_c at each target, to see how little the
# adhesive stiffness moves the elastic plateau.
if "kc_preparation" in t and len(set(t["kc_preparation"])) > 1:
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    targets = sorted(set(t["phi_target"]))
    k2 = t["kn_mean"]
    for n, phi in enumerate(targets):
        sel = np.where(jammed & (t["phi_target"] == phi) & (t["kt_kn"] == t["kt_kn"][0]))[0]
        sel = sel[np.argsort(t["kc_preparation"][sel])]
        if len(sel) == 0:
            continue
        for ax, m in zip(axes, ("K", "G")):
            ax.plot(t["kc_preparation"][sel] / k2[sel], t[m + "_star"][sel], "o-",
                    color="C%d" % n, ms=4, label="phi %.3f" % phi)
    for ax, m in zip(axes, ("K", "G")):
        ax.set_xscale("symlog", linthresh=0.1)
        ax.set_xlabel("k_c / k_2 of the preparation (and the probe)")
        ax.set_ylabel(m + "* = " + m + " dbar / k_2")
        ax.legend(fontsize=7)
    if title:
        fig.suptitle(title, fontsize=10)
    save(fig, outdir, "moduli_vs_cohesion.png")

# Reversibility (probe.prestrains): after a pre-strain of growing size, the modulus of the
# first small reversal against the secant modulus of the pre-strain (1: elastic), and the
# stress left once the whole pre-strain is reversed (0: reversible).
if reversibility:
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for n, (name, r) in enumerate(sorted(reversibility.items())):
        for mode, marker, word in ((0, "o", "isotropic (K)"), (1, "s", "shear (G)")):
            sel = r["mode"] == mode
            e = r["prestrain"][sel]
            axes[0].plot(e, r["unloading_modulus_star"][sel] / r["loading_modulus_star"][sel],
                         marker + "-", color="C%d" % n, ms=4, label="%s, %s" % (name, word))
            axes[1].plot(e, np.abs(r["residual"][sel]), marker + "-", color="C%d" % n, ms=4,
                         label="%s, %s" % (name, word))
    axes[0].axhline(1, color="k", lw=0.6)
    axes[0].set_ylabel("unloading modulus / loading (secant) modulus")
    axes[1].set_ylabel("|stress left after full reversal| / pre-strain stress", fontsize=9)
    axes[1].set_yscale("log")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("pre-strain")
        ax.legend(fontsize=6)
    if title:
        fig.suptitle(title + ": reversibility", fontsize=10)
    save(fig, outdir, "reversibility.png")

# Non-affine fluctuation of the isotropic probe against the fluctuation theory: the full
# relative displacement (eta_K), its normal part (eta_K_normal, unsigned) and the signed
# fraction of the affine normal approach that the relaxation undoes, which FT predicts as
# 2 rho (first ring) or 2 (rho + rho_s) (second ring): K^FT = (1 - 2 (rho + rho_s)) K^EMT.
if "normal_relaxation_K" in t and np.any(jammed):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for n, (key, idx) in enumerate(sorted(series.items())):
        idx = np.array(idx)
        idx = idx[jammed[idx]]
        if len(idx) == 0:
            continue
        x = t["phi"][idx] * t["z_corrected"][idx]
        o = np.argsort(x)
        c = "C%d" % n
        lab = label_of(key)
        ax.plot(x[o], t["eta_K"][idx][o], "o", color=c, mfc="none", ms=4,
                label="eta_K (full), " + lab)
        ax.plot(x[o], t["eta_K_normal"][idx][o], "s", color=c, mfc="none", ms=4,
                label="eta_K normal part, " + lab)
        ax.plot(x[o], t["normal_relaxation_K"][idx][o], "o", color=c, ms=5,
                label="normal relaxation (signed), " + lab)
        ax.plot(x[o], 2 * t["rho"][idx][o], ":", color=c, lw=1,
                label="FT 2 rho" if n == 0 else None)
        ax.plot(x[o], 2 * (t["rho"][idx][o] + t["rho_s"][idx][o]), "-", color=c, lw=1,
                label="FT 2 (rho + rho_s)" if n == 0 else None)
    ax.set_yscale("log")
    ax.set_xlabel("phi Z")
    ax.set_ylabel("non-affine / affine (isotropic probe)")
    ax.legend(fontsize=6)
    if title:
        ax.set_title(title, fontsize=9)
    save(fig, outdir, "nonaffine_vs_theory.png")
