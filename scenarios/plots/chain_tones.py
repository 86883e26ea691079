"""Charts of the chain_tones scene: space-time maps (displacement, bead energy, spectral
energy) of one realization, band-energy curves (one realization against the ensemble, the
agitated band against xi, several bands at one xi) and the fitting procedures' view."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    B, N, L = int(f.attrs["bands"]), int(f.attrs["beads"]), int(f.attrs["sites"])
    r0 = int(f.attrs["mapped_realization"])
    w1 = (int(f.attrs["window_nonlinear_first"]), int(f.attrs["window_nonlinear_last"]))
    w2 = (int(f.attrs["window_linear_first"]), int(f.attrs["window_linear_last"]))
    runs = []
    for g in sorted((g for g in f if g.startswith("xi_")), key=lambda s: int(s[3:])):
        d = f[g]
        tones = {}
        for name in d:
            if not name.startswith("tone_"):
                continue
            t = d[name]
            key = (int(t.attrs["tone"]), float(t.attrs["u0"]))
            tones[key] = {k: t[k][:] for k in ("bands_mean", "bands_one", "spectrum_one",
                                               "u_one", "te_one")}
            tones[key]["band"] = int(t.attrs["band"])
        fit = d["fits"]
        runs.append(dict(xi=float(d.attrs["xi"]), t=d["times"][:], tones=tones,
                         fit=dict(decay=fit["decay"][:], rise=fit["rise"][:],
                                  d1=fit["decay_nonlinear"][:], r1=fit["rise_nonlinear"][:],
                                  lin=fit["linear_slopes"][:], tone=int(fit.attrs["tone"]),
                                  s=int(fit.attrs["agitated_band"]),
                                  r=int(fit.attrs["neighbour_band"]))))

tone_list = sorted({k[0] for k in runs[0]["tones"]})
u0_first = max(k[1] for k in runs[0]["tones"])
pick = [runs[0], runs[-1]] if len(runs) > 1 else runs  # the lowest and the highest xi


def space_time(field, title, label, cmap, symmetric):
    fig, axes = plt.subplots(1, len(pick), figsize=(4.2 * len(pick), 3.4), squeeze=False)
    for ax, run in zip(axes[0], pick):
        m = run["tones"][(tone_list[0], u0_first)][field]
        lim = np.abs(m).max() or 1.0
        im = ax.imshow(m, origin="lower", aspect="auto", cmap=cmap,
                       extent=[run["t"][0], run["t"][-1], 1, N],
                       vmin=-lim if symmetric else 0, vmax=lim)
        ax.set_title(f"xi = {run['xi']:g}, tone N = {tone_list[0]}, realization {r0}")
        ax.set_xlabel("time (t_c)")
        ax.set_ylabel("bead p")
        fig.colorbar(im, ax=ax, label=label)
    fig.suptitle(title)
    save(fig, outdir, f"{field.replace('_one', '')}_space_time.png")


space_time("u_one", "displacement u_p(t)", "u / Delta_0", "RdBu_r", True)
space_time("te_one", "bead energy TE_p(t)", "TE_p", "magma", False)

# Spectral energy of one realization for the lowest tone above the fundamental and the highest.
spec_tones = [t for t in tone_list if t > 1][:1] + [tone_list[-1]]
run = runs[-1]
fig, axes = plt.subplots(1, len(spec_tones), figsize=(4.2 * len(spec_tones), 3.4), squeeze=False)
for ax, tone in zip(axes[0], spec_tones):
    m = run["tones"][(tone, u0_first)]["spectrum_one"]
    im = ax.imshow(np.log10(np.maximum(m, 1e-8)), origin="lower", aspect="auto", cmap="viridis",
                   extent=[run["t"][0], run["t"][-1], 0, m.shape[0] - 1], vmin=-8, vmax=0)
    ax.set_title(f"xi = {run['xi']:g}, tone N = {tone}")
    ax.set_xlabel("time (t_c)")
    ax.set_ylabel("wavenumber bin j (k = 2 pi j / L)")
    fig.colorbar(im, ax=ax, label="log10 TE^(k) / E")
fig.suptitle(f"spectral energy of realization {r0}")
save(fig, outdir, "spectral_energy_space_time.png")

# Band-energy curves.
fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
tone = runs[-1]["fit"]["tone"]
s = runs[-1]["fit"]["s"]
ax = axes[0]
for run in runs:
    tr = run["tones"][(tone, u0_first)]
    line, = ax.plot(run["t"], tr["bands_mean"][s], label=f"xi = {run['xi']:g} ensemble")
    ax.plot(run["t"], tr["bands_one"][s], ":", color=line.get_color(),
            label=f"xi = {run['xi']:g} realization {r0}")
ax.set_title(f"agitated band {s} (tone N = {tone})")
ax.set_xlabel("time (t_c)")
ax.set_ylabel("normalized band energy")
ax.legend(fontsize=6)
ax = axes[1]
run = runs[-1]
tr = run["tones"][(tone, u0_first)]
for r in range(max(0, s - 2), min(B, s + 4)):
    ax.plot(run["t"], tr["bands_mean"][r], label=f"band {r}")
ax.set_yscale("log")
ax.set_ylim(1e-6, 1.5)
ax.set_title(f"several bands at xi = {run['xi']:g}")
ax.set_xlabel("time (t_c)")
ax.legend(fontsize=6)
ax = axes[2]
for run in runs:
    ax.plot(run["t"], run["tones"][(tone, u0_first)]["bands_mean"][s], label=f"xi = {run['xi']:g}")
ax.set_title(f"band {s} against disorder")
ax.set_xlabel("time (t_c)")
ax.legend(fontsize=7)
save(fig, outdir, "band_energy_curves.png")

# What the fitting procedures see, at the highest xi.
run = runs[-1]
fit, t = run["fit"], run["t"]
fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
y1, z1 = fit["d1"]
y2, z2 = fit["r1"]
x1, x2 = fit["lin"]
for ax, data, model1, model2, title in (
        (axes[0], fit["decay"], (1 - y1) * np.exp(-z1 * t) + y1, 1 - x1 * t,
         f"decay of the agitated band {fit['s']}"),
        (axes[1], fit["rise"], y2 * (1 - np.exp(-z2 * t)), x2 * t,
         f"rise of band {fit['r']}")):
    ax.plot(t, data, "k.", ms=3, label="ensemble")
    a, b = w1
    ax.plot(t[a:b + 1], model1[a:b + 1], "C0-", lw=2, label=f"procedure 1 (samples {a}-{b})")
    ax.plot(t, model1, "C0:", lw=1)
    a, b = w2
    ax.plot(t[a:b + 1], model2[a:b + 1], "C1-", lw=2, label=f"procedure 2 (samples {a}-{b})")
    ax.set_xlim(t[0], min(t[-1], 4 * t[w1[1]] if w1[1] < len(t) else t[-1]))
    ax.set_ylim(min(0.0, data.min()), 1.15 * data.max())
    ax.set_title(f"xi = {run['xi']:g}: {title}")
    ax.set_xlabel("time (t_c)")
    ax.legend(fontsize=7)
save(fig, outdir, "fit_views.png")
