"""Shared helpers for the charts of every scene: headless matplotlib and atomic PNG writes."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def save(fig, outdir, name):
    """Write <outdir>/<name> through a temporary name, so a chart is never half-written."""
    path = os.path.join(outdir, name)
    tmp = os.path.join(outdir, "." + name + ".partial")
    fig.tight_layout()
    fig.savefig(tmp, dpi=120, format="png")
    plt.close(fig)
    os.replace(tmp, path)
    return path
