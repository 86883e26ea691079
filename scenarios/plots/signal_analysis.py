"""Charts of the signal_analysis scene: traces with their picks, first-event energy spectra
and the spectral-ratio fit (recorded traces), or the estimator's error of 1/Q against noise
per window and band fraction (synthetic validation)."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    if f.attrs["synthetic"] > 0:
        e = f["estimator"]
        names = e.attrs["windows"]
        names = (names.decode() if isinstance(names, bytes) else names).split(",")
        noise, frac, win = e["noise"][:], e["band_fraction"][:], e["window"][:]
        mean, sd = e["mean_relative_error"][:], e["sd_relative_error"][:]
        fig, axes = plt.subplots(1, len(names), figsize=(3.2 * len(names), 3.3), sharey=True)
        for w, ax in enumerate(axes):
            for fr in sorted(set(frac)):
                sel = (win == w) & (frac == fr)
                ax.errorbar(noise[sel], mean[sel], yerr=sd[sel], marker="o", capsize=2,
                            label=f"band > {fr:g} of max")
            ax.set_xscale("log")
            ax.axhline(0, color="0.6", lw=0.6)
            ax.set_title(f"window: {names[w]}")
            ax.set_xlabel("noise (of source peak)")
        axes[0].set_ylabel("relative error of 1/Q (mean, sd)")
        axes[0].legend(fontsize=7)
        save(fig, outdir, "estimator_error.png")
    else:
        traces = [k for k in ("trace1", "trace2") if k in f]
        fig, axes = plt.subplots(1, 3 if "ratio" in f else 2, figsize=(12, 3.4))
        for k in traces:
            g = f[k]
            t, a = g["time"][:], g["amplitude"][:]
            line, = axes[0].plot(t, a, lw=0.9, label=k)
            for pick, m in (("first_arrival", "|"), ("first_peak", "^"), ("first_trough", "v")):
                tp = g.attrs[pick]
                if np.isfinite(tp):
                    axes[0].plot([tp], [np.interp(tp, t, a)], m, color=line.get_color(), ms=7)
            s = g["spectrum"]
            fr, en = s["frequency"][:], s["energy"][:]
            axes[1].semilogy(fr, en / en.max(), lw=0.9, label=k)
        axes[0].set_xlabel("time")
        axes[0].set_ylabel("amplitude (| arrival, ^ peak, v trough)")
        axes[0].legend(fontsize=7)
        axes[1].set_xlabel("frequency")
        axes[1].set_ylabel("|A(f)|^2 / max")
        axes[1].set_ylim(1e-6, 2)
        if "ratio" in f:
            r = f["ratio"]
            fr, y = r["frequency"][:], r["log_ratio"][:]
            axes[2].plot(fr, y, ".", ms=3, label="ln |A2/A1|")
            axes[2].plot(fr, r.attrs["intercept"] + r.attrs["slope"] * fr, "k-",
                         label=f"fit: Q = {r.attrs['Q']:.3g}")
            axes[2].set_xlabel("frequency")
            axes[2].legend(fontsize=7)
        save(fig, outdir, "signals.png")
