"""Charts of the impact scene: contact force against time per incidence angle, rebound
quantities against the incidence angle (with the gross-sliding closed forms), and the
measured restitution against impact speed for both mappings of e to the damping."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    e_in = f.attrs["restitution_input"]
    names = sorted(f["oblique"], key=lambda s: int(s.split("_")[1]))
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    for name in names:
        g = f["oblique"][name]
        t, fn, ft = g["time"][:], g["normal_force"][:], g["tangential_force"][:]
        inside = fn != 0
        t0 = t[inside][0] if inside.any() else 0.0
        label = f"{g.attrs['angle_deg']:g} deg"
        axes[0].plot(t[inside] - t0, fn[inside], lw=1.1, label=label)
        axes[1].plot(t[inside] - t0, ft[inside], lw=1.1, label=label)
    axes[0].set_ylabel("normal force (N)")
    axes[1].set_ylabel("tangential force (N)")
    for ax in axes:
        ax.set_xlabel("time since first contact (us)")
        ax.axhline(0, color="0.6", lw=0.6)
    axes[0].legend(fontsize=7)
    save(fig, outdir, "force_vs_time.png")

    a = f["angles"]
    ang = a["angle_deg"][:]
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4))
    axes[0].plot(ang, a["restitution_tangential"][:], "o-", label="measured")
    axes[0].plot(ang, a["closed_form_restitution_tangential"][:], "k--", label="gross sliding")
    axes[0].set_ylabel("tangential restitution e_t")
    axes[1].plot(ang, a["spin_out_scaled"][:], "o-", label="measured")
    axes[1].plot(ang, a["closed_form_spin_out_scaled"][:], "k--", label="gross sliding")
    axes[1].set_ylabel("rebound spin  w R / v")
    axes[2].plot(ang, a["rebound_angle_deg"][:], "o-", label="measured")
    axes[2].plot(ang, a["closed_form_rebound_angle_deg"][:], "k--", label="gross sliding")
    axes[2].set_ylabel("rebound angle (deg)")
    for ax in axes:
        ax.set_xlabel("incidence angle (deg)")
        ax.legend(fontsize=7)
    save(fig, outdir, "rebound_vs_angle.png")

    s = f["speed_sweep"]
    v = s["speed"][:]
    fig, ax = plt.subplots(figsize=(4.6, 3.4))
    ax.semilogx(v * 1e3, s["restitution_exact_mapping"][:], "o-", label="exact alpha(e)")
    ax.semilogx(v * 1e3, s["restitution_common_mapping"][:], "s--", label="common sqrt(5) beta(e)")
    ax.axhline(e_in, color="k", lw=0.8, ls=":", label="input e")
    ax.set_xlabel("impact speed (m/s)")
    ax.set_ylabel("measured restitution")
    ax.legend(fontsize=7)
    save(fig, outdir, "restitution_vs_speed.png")
