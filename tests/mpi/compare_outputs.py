#!/usr/bin/python3
"""Compares two output folders of the same scene bit for bit: summary.json (every number as
written, the run record and wall-time figures left out, the folder names made equal) and
results.h5 (every dataset's type, shape and raw bytes, every attribute). Exit status 0 when
they are the same, 1 with the differences listed otherwise."""
import json
import sys

import h5py
import numpy as np

TIMING_KEYS = {"run", "wall_seconds", "wall_time_s", "bead_steps_per_second",
               "seconds_per_realization", "seconds", "ensemble_seconds",
               "master_equation_seconds"}


def strip(x, a, b):
    if isinstance(x, dict):
        return {k: strip(v, a, b) for k, v in x.items()
                if k not in TIMING_KEYS and "seconds" not in k and "per_second" not in k
                and not k.startswith("speedup") and not k.startswith("cost")}
    if isinstance(x, list):
        return [strip(v, a, b) for v in x]
    if isinstance(x, str):
        return x.replace(a, b)
    return x


def h5_items(path):
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            for k, v in obj.attrs.items():
                out["attr " + name + "@" + k] = v.tobytes() if isinstance(v, np.ndarray) else v
            if isinstance(obj, h5py.Dataset):
                data = obj[()]
                out["data " + name] = (str(obj.dtype), obj.shape,
                                       data.tobytes() if isinstance(data, np.ndarray) else data)
        for k, v in f.attrs.items():
            out["attr /@" + k] = v.tobytes() if isinstance(v, np.ndarray) else v
        f.visititems(visit)
    return out


def main():
    a, b = sys.argv[1], sys.argv[2]
    problems = []
    with open(a + "/summary.json") as fa, open(b + "/summary.json") as fb:
        ja = strip(json.load(fa), a, b)
        jb = strip(json.load(fb), b, b)
    if ja != jb:
        for k in sorted(set(ja) | set(jb)):
            if ja.get(k) != jb.get(k):
                problems.append("summary.json: '%s' differs" % k)
    ha, hb = h5_items(a + "/results.h5"), h5_items(b + "/results.h5")
    for k in sorted(set(ha) | set(hb)):
        va, vb = ha.get(k), hb.get(k)
        if isinstance(va, (bytes, str)) and isinstance(vb, (bytes, str)):
            va = va.replace(a, b) if isinstance(va, str) else va
        if k not in ha or k not in hb or va != vb:
            if k.startswith("attr") and any(t in k for t in ("seconds", "per_second")):
                continue
            problems.append("results.h5: %s differs" % k)
    if problems:
        print("\n".join(problems[:40]))
        return 1
    print("same: %s and %s (%d HDF5 items)" % (a, b, len(ha)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
