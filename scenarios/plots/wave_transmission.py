"""Charts of the wave_transmission scene: source pulse and received signals per wall stress
(normalised), first-event spectra of the receiver wall, M from the time of flight against M
from the quasi-static probe, and the spectral ratio between the two slabs."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    n = int(f.attrs["states"])
    # A state the servo did not converge to has no group (summary.json: unconverged_states).
    analysed = [k for k in range(n) if f"pressure_{k}" in f]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    for k in analysed:
        g = f[f"pressure_{k}"]
        lab = f"{g.attrs['sigma_xx']:.3g} MPa"
        r = g["receiver"]
        t, a = r["time"][:], r["amplitude"][:]
        line, = axes[0].plot(t, a / np.max(np.abs(a)), lw=1, label=lab)
        if np.isfinite(r.attrs["first_peak"]):
            axes[0].axvline(r.attrs["first_peak"], color=line.get_color(), lw=0.6, ls=":")
        for s in range(4):
            name = f"slab_{s}"
            if name in g:
                sl = g[name]
                b = sl["amplitude"][:]
                axes[1].plot(sl["time"][:], b / np.max(np.abs(b)) + 2.2 * s, lw=0.8,
                             color=line.get_color())
        sp = r["spectrum"]
        e = sp["energy"][:]
        axes[2].semilogy(sp["frequency"][:] * 1e3, e / e.max(), lw=1, label=lab,
                         color=line.get_color())
        sm = g["receiver_mirrored"]
        e = sm["energy"][:]
        axes[2].semilogy(sm["frequency"][:] * 1e3, e / e.max(), lw=0.8, ls="--",
                         color=line.get_color())
    if analysed:
        s0 = f[f"pressure_{analysed[0]}/source"]
        axes[0].plot(s0["time"][:], s0["amplitude"][:] / np.max(s0["amplitude"][:]), "k--",
                     lw=0.8, label="source velocity")
    axes[0].set_xlabel("time (us)")
    axes[0].set_ylabel("receiver wall stress (normalised)")
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("time (us)")
    axes[1].set_ylabel("slab velocity (normalised, offset per slab)")
    axes[2].set_xlabel("frequency (kHz)")
    axes[2].set_ylabel("|A(f)|^2 / max (receiver; dashed: mirrored)")
    axes[2].set_xlim(0, 60)
    axes[2].set_ylim(1e-6, 2)
    save(fig, outdir, "signals.png")

    t = f["table"]
    p = t["sigma_xx"][:]
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
    axes[0].loglog(p, t["M_wave"][:], "o-", label="rho V_p^2 (first peak, wall to wall)")
    axes[0].loglog(p, t["M_probe"][:], "s-", label="quasi-static uniaxial probe")
    axes[0].set_xlabel("wall stress sigma_xx (MPa)")
    axes[0].set_ylabel("M (MPa)")
    axes[0].legend(fontsize=7)
    for k in analysed:
        g = f[f"pressure_{k}"]
        if "ratio" in g:
            fr, y = g["ratio/frequency"][:], g["ratio/log_ratio"][:]
            line, = axes[1].plot(fr * 1e3, y, ".", ms=3)
            axes[1].plot(fr * 1e3, g["ratio"].attrs["intercept"] + g["ratio"].attrs["slope"] * fr,
                         color=line.get_color(),
                         label=f"{g.attrs['sigma_xx']:.3g} MPa: Q = {t['Q'][k]:.3g}")
    axes[1].set_xlabel("frequency (kHz)")
    axes[1].set_ylabel("ln |A_far slab / A_near slab|")
    axes[1].legend(fontsize=7)
    save(fig, outdir, "moduli_and_q.png")

# Numerics: picked travel time and Q against the time step, and Q against the contacts'
# restitution (1: no contact damping), from summary.json when the run made those checks.
import json
import os

summary_path = os.path.join(outdir, "summary.json")
if os.path.exists(summary_path):
    with open(summary_path) as fh:
        states = json.load(fh).get("states", [])

    def travel(e):
        v = e.get("travel", {}).get("first_peak", {}).get("travel_time")
        return np.nan if v is None else v

    def q_of(e):
        v = e.get("Q")
        return v if isinstance(v, (int, float)) else np.nan

    if any(s.get("dt_check") or s.get("restitution_check") for s in states):
        fig, axes = plt.subplots(1, 3, figsize=(13, 3.5))
        for s in states:
            lab = f"{s['sigma_xx']:.3g} MPa"
            ref = s.get("reference_numerics")
            pts = ([ref] if ref else []) + list(s.get("dt_check", []))
            pts = sorted(pts, key=lambda e: e["dt"])
            if pts:
                dt = [e["dt"] for e in pts]
                t0 = travel(pts[0])
                axes[0].plot(dt, [travel(e) / t0 - 1 for e in pts], "o-", label=lab)
                axes[1].plot(dt, [q_of(e) for e in pts], "o-", label=lab)
            rs = list(s.get("restitution_check", []))
            if ref and isinstance(ref.get("restitution"), (int, float)):
                rs.append(ref)
            if rs:
                rs = sorted(rs, key=lambda e: e["restitution"])
                axes[2].plot([e["restitution"] for e in rs], [q_of(e) for e in rs], "o-",
                             label=lab)
        axes[0].axhspan(-0.01, 0.01, color="0.9")
        axes[0].set_xlabel("time step (us)")
        axes[0].set_ylabel("first-peak travel time / smallest-dt value - 1")
        axes[1].set_xlabel("time step (us)")
        axes[1].set_ylabel("Q (spectral ratio, slabs)")
        axes[2].set_xlabel("contact restitution e (1: no contact damping)")
        axes[2].set_ylabel("Q (spectral ratio, slabs)")
        for ax in axes:
            ax.legend(fontsize=7)
        save(fig, outdir, "numerics.png")
