"""One chart of the linear and the Hertz element-test studies against the theories: K* and G*
against phi Z for every preparation friction of both studies, with EMT (a curve per study:
it depends on phi Z and k_t/k_n only) and the second-ring fluctuation theory with the
measured chi (markers: it differs per configuration); for G also EMT with the k_t/k_n = 0.88
the source's theory takes for Hertz (the Mindlin springs here give 0.593). Hertz moduli are shown normalised by
the mean tangent stiffness dF/d(delta) (the engine's K* = K dbar / k_n, as the theories take
it) and, open markers, by the secant stiffness F/delta = (2/3) of it, the source's choice.

Usage: moduli_combined.py LINEAR_RESULTS_H5 HERTZ_RESULTS_H5 OUTDIR"""
import sys

import h5py
import numpy as np

from chartkit import plt, save

linear_h5, hertz_h5, outdir = sys.argv[1], sys.argv[2], sys.argv[3]


def table(path):
    with h5py.File(path, "r") as f:
        t = {k: f["table"][k][:] for k in f["table"]}
    jammed = t["jammed"] > 0 if "jammed" in t else t["z_corrected"] > 0
    return t, jammed


studies = [("linear", table(linear_h5), "o", "-"), ("Hertz", table(hertz_h5), "s", "--")]
fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
for ax, m in zip(axes, ("K", "G")):
    for name, (t, jammed), marker, ls in studies:
        mus = sorted(set(t["mu_preparation"][jammed]))
        for n, mu in enumerate(mus):
            sel = np.where(jammed & (t["mu_preparation"] == mu))[0]
            x = t["phi"][sel] * t["z_corrected"][sel]
            c = plt.cm.viridis(n / max(1, len(mus) - 1))
            ax.plot(x, t[m + "_star"][sel], marker, color=c, ms=5,
                    label="%s, mu %g" % (name, mu))
            if name == "Hertz":  # the source's secant normalisation: 3/2 of the tangent one
                ax.plot(x, 1.5 * t[m + "_star"][sel], marker, color=c, ms=5, mfc="none",
                        label="Hertz by secant stiffness" if n == 0 else None)
            ax.plot(x, t[m + "_ft2"][sel], "x", color=c, ms=5,
                    label="FT2 (measured chi)" if (n == 0 and name == "linear") else None)
        sel = np.where(jammed)[0]
        x = t["phi"][sel] * t["z_corrected"][sel]
        o = np.argsort(x)
        ax.plot(x[o], t[m + "_emt"][sel][o], ls, color="k", lw=0.9,
                label="EMT, %s (k_t/k_n %.3g)" % (name, t["kt_kn"][sel][0]))
        if m == "G" and name == "Hertz":  # the source's theory takes k_t/k_n = 0.88
            r = t["kt_kn"][sel][0]
            ax.plot(x[o], t["G_emt"][sel][o] * (1 + 1.5 * 0.88) / (1 + 1.5 * r), ":",
                    color="k", lw=0.9, label="EMT, Hertz with the source's k_t/k_n 0.88")
    ax.set_xlabel("phi Z")
    ax.set_ylabel(m + "* = " + m + " dbar / k_n (tangent)")
    ax.legend(fontsize=6, ncol=2)
fig.suptitle("Linear and Hertz packings (N = 4096, unloading branch) against EMT and FT",
             fontsize=10)
save(fig, outdir, "moduli_linear_and_hertz.png")
