"""Charts of the impact_benchmarks scene: force against overlap of the normal impacts (tests
1, 2) beside elastic Hertz, measured against input restitution (test 3), and for each
oblique or spinning test (4 to 8) the tangential restitution, rebound spin, rebound angle and
impulse ratio against the normalised incidence v_c / (mu (1 + e) v_n), beside rigid-body
gross sliding (which holds above 7/2)."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    cases = {name: f["cases"][name] for name in f["cases"]}

    def by_test(*tests):
        return [(n, g) for n, g in sorted(cases.items()) if int(g.attrs["test"]) in tests]

    normal = by_test(1, 2)
    if normal:
        fig, axes = plt.subplots(1, len(normal), figsize=(3.2 * len(normal), 3.2), squeeze=False)
        for ax, (name, g) in zip(axes[0], normal):
            d, fn = g["first/overlap"][:], g["first/normal_force"][:]
            inside = d > 0
            ax.plot(d[inside] * 1e3, fn[inside], lw=1.2, label="engine")
            k = g["first"].attrs["hertz_stiffness"]
            dd = np.linspace(0, d.max(), 100)
            ax.plot(dd * 1e3, k * dd**1.5, "k--", lw=0.9, label="elastic Hertz")
            ax.set_title(name, fontsize=8)
            ax.set_xlabel("overlap (um)")
            ax.set_ylabel("normal force (N)")
            ax.legend(fontsize=7)
        save(fig, outdir, "normal_impacts.png")

    rest = by_test(3)
    if rest:
        fig, ax = plt.subplots(figsize=(4.2, 3.4))
        for name, g in rest:
            ax.plot(g["restitution_input"][:], g["restitution_normal"][:], "o-", label=name)
        ax.plot([0, 1], [0, 1], "k--", lw=0.8, label="input")
        ax.set_xlabel("input restitution")
        ax.set_ylabel("measured restitution")
        ax.legend(fontsize=7)
        save(fig, outdir, "restitution.png")

    for test in (4, 5, 6, 7, 8):
        group = by_test(test)
        if not group:
            continue
        fig, axes = plt.subplots(1, 4, figsize=(14, 3.3))
        for name, g in group:
            # Slips of either sign drawn as the positive one: |v_c| on x, the odd quantities
            # (spin change, impulse, rebound angle) times the slip's sign.
            x = g["normalised_incidence"][:]
            sgn = np.where(x < 0, -1.0, 1.0)
            x = np.abs(x)
            mu, vn = g["friction"][:], g["normal_speed"][:]
            e = g["restitution_normal"][:]
            a = g.attrs["radius"]
            scale = mu * (1 + e) * vn  # what gross sliding changes the slip by, over 7/2
            line, = axes[0].plot(x, g["restitution_tangential"][:], "o-", ms=3, label=name)
            c = line.get_color()
            cf = dict(color="k", lw=1.0, ls="--", zorder=3)
            axes[0].plot(x, g["closed_form_restitution_tangential"][:], **cf)
            dw = sgn * (g["spin_out"][:] - g["spin_in"][:]) * a / scale
            axes[1].plot(x, dw, "o-", ms=3, color=c)
            axes[1].plot(x, sgn * (g["closed_form_spin_out"][:] - g["spin_in"][:]) * a / scale, **cf)
            axes[2].plot(x, sgn * g["rebound_angle_deg"][:], "o-", ms=3, color=c)
            axes[2].plot(x, sgn * g["closed_form_rebound_angle_deg"][:], **cf)
            axes[3].plot(x, sgn * g["impulse_ratio"][:] / mu, "o-", ms=3, color=c)
            axes[3].plot(x, sgn * g["closed_form_impulse_ratio"][:] / mu, **cf)
        axes[0].set_ylabel("tangential restitution  -v'_c / v_c")
        axes[1].set_ylabel("spin change  a dw / (mu (1+e) v_n)")
        axes[2].set_ylabel("contact-point rebound angle (deg)")
        axes[3].set_ylabel("J_t / (mu J_n)")
        for ax in axes:
            ax.set_xlabel("normalised incidence  |v_c| / (mu (1+e) v_n)")
            ax.axvline(3.5, color="0.7", lw=0.7, ls=":")
        axes[0].legend(fontsize=7, title="points: engine; black dashed: gross sliding",
                       title_fontsize=7)
        title = group[0][1].attrs["title"]
        title = title.decode() if isinstance(title, bytes) else str(title)
        fig.suptitle(title.split(":")[0], fontsize=9)
        save(fig, outdir, f"test{test}.png")
