"""Row-by-row comparison of two elastic_moduli studies of the same packing protocol (a
halving check at full size: the same seed and targets, one parameter changed): for every
configuration present in both (matched on preparation friction and target density) the
coordination, pressure and moduli of each and their relative change, as a Markdown table,
and the largest changes over the jammed rows.

Usage: compare_moduli_tables.py BASE_RESULTS_H5 OTHER_RESULTS_H5 OUT_MD [LABEL_BASE LABEL_OTHER]"""
import os
import sys

import h5py
import numpy as np

base_h5, other_h5, out_md = sys.argv[1], sys.argv[2], sys.argv[3]
labels = sys.argv[4:6] if len(sys.argv) >= 6 else ["base", "other"]


def rows(path):
    with h5py.File(path, "r") as f:
        t = {k: f["table"][k][:] for k in f["table"]}
    jammed = t["jammed"] > 0 if "jammed" in t else t["z_corrected"] > 0
    target = t["phi_target"] if "phi_target" in t else t["phi"]
    out = {}
    for i in range(len(t["phi"])):
        key = (round(float(np.nan_to_num(t["mu_preparation"][i], nan=-1)), 9),
               round(float(target[i]), 6), round(float(t["kt_kn"][i]), 9))
        out[key] = {"jammed": bool(jammed[i]), **{k: float(t[k][i]) for k in
                    ("phi", "z_corrected", "pressure_star", "K_star", "G_star")}}
    return out


a, b = rows(base_h5), rows(other_h5)
common = sorted(set(a) & set(b), key=lambda k: (k[0], -k[1], k[2]))
if not common:
    sys.exit("no configuration in common (matched on preparation mu, target phi and kt/kn)")
quantities = (("Z", "z_corrected"), ("P*", "pressure_star"), ("K*", "K_star"), ("G*", "G_star"))
lines = ["| mu | phi | " + " | ".join("%s %s | %s %s | change" % (q, labels[0], q, labels[1])
                                      for q, _ in quantities) + " |",
         "|---|---|" + "---|---|---|" * len(quantities)]
worst = {q: 0.0 for q, _ in quantities}
for key in common:
    ra, rb = a[key], b[key]
    cells = []
    for q, col in quantities:
        va, vb = ra[col], rb[col]
        rel = (vb - va) / abs(va) if va != 0 else float("nan")
        if ra["jammed"] and rb["jammed"] and np.isfinite(rel):
            worst[q] = max(worst[q], abs(rel))
        fmt = "%.3e" if q == "P*" else "%.4f"
        cells.append("%s | %s | %+.2f %%" % (fmt % va, fmt % vb, 100 * rel))
    state = "" if ra["jammed"] and rb["jammed"] else " (unjammed)"
    lines.append("| %g | %.3f%s | %s |" % (key[0], ra["phi"], state, " | ".join(cells)))
lines.append("")
lines.append("Largest relative change over the configurations jammed in both: " +
             ", ".join("%s %.2f %%" % (q, 100 * worst[q]) for q, _ in quantities) + ".")
tmp = out_md + ".partial"
with open(tmp, "w") as f:
    f.write("\n".join(lines) + "\n")
os.replace(tmp, out_md)
print("\n".join(lines))
