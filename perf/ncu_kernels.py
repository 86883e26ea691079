#!/usr/bin/python3
"""Per-step kernel time and DRAM traffic of a DEM step from an Nsight Compute CSV.

    ncu --metrics gpu__time_duration.sum,dram__bytes_read.sum,dram__bytes_write.sum \\
        --print-units base --launch-skip S --launch-count C --csv bench_dem_throughput ... > k.csv
    /usr/bin/python3 perf/ncu_kernels.py N k.csv [k2.csv ...]

The kernels are grouped by the engine function their functor comes from (the names carry
it); a step is one kick-drift kernel, so the figures are per step of the window profiled
(every group's sum divided by the number of kick-drift kernels seen). "other" holds the
neighbour rebuilds that fell in the window (their share depends on the window's length).
DRAM bytes are per particle and step (N particles).
"""
import csv
import sys
from collections import OrderedDict

GROUPS = [
    ("contacts", "compute_contact_rows"),
    ("gather", "gather_contact_forces"),
    ("kick_drift", "kick_drift"),
    ("kick_drift", "KickDriftPass"),  # the pass as a functor class: its name, not its function's
    ("kick", "kick<"),
]
SCALE = {"": 1.0, "byte": 1.0, "Kbyte": 1e3, "Mbyte": 1e6, "Gbyte": 1e9,
         "nsecond": 1.0, "usecond": 1e3, "msecond": 1e6, "second": 1e9}


def group_of(name):
    for label, key in GROUPS:
        if key in name:
            return label
    return "other"


def summarize(n, path):
    kernels = OrderedDict()  # (id) -> {group, metrics}
    with open(path, newline="") as f:
        lines = [l for l in f if l.startswith('"')]  # skip the profiler's own messages
    for row in csv.DictReader(lines):
        k = kernels.setdefault(row["ID"], {"group": group_of(row["Kernel Name"]),
                                           "grid": row.get("Grid Size", ""),
                                           "block": row.get("Block Size", "")})
        value = float(row["Metric Value"].replace(",", ""))
        k[row["Metric Name"]] = value * SCALE.get(row.get("Metric Unit", ""), 1.0)
    sums = OrderedDict()
    for k in kernels.values():
        s = sums.setdefault(k["group"], {"ns": 0.0, "bytes": 0.0, "launches": 0,
                                         "grid": k["grid"], "block": k["block"]})
        s["ns"] += k.get("gpu__time_duration.sum", 0.0)
        s["bytes"] += k.get("dram__bytes_read.sum", 0.0) + k.get("dram__bytes_write.sum", 0.0)
        s["launches"] += 1
    steps = sums.get("kick_drift", {}).get("launches", 0)
    if steps == 0:
        sys.exit(f"{path}: no kick-drift kernel in the window")
    print(f"{path}: {steps} steps, N = {n}")
    print(f"{'kernel':<12} {'us/step':>9} {'DRAM B/particle':>16} {'TB/s':>6}  grid x block")
    total_ns = total_b = 0.0
    for g, s in sums.items():
        ns, b = s["ns"] / steps, s["bytes"] / steps
        total_ns += ns
        total_b += b
        rate = b / ns / 1e3 if ns > 0 else 0.0
        shape = f"{s['grid']} x {s['block']}" if g != "other" else f"{s['launches']} launches"
        print(f"{g:<12} {ns / 1e3:9.1f} {b / n:16.0f} {rate:6.2f}  {shape}")
    print(f"{'per step':<12} {total_ns / 1e3:9.1f} {total_b / n:16.0f} "
          f"{total_b / total_ns / 1e3:6.2f}")


def main(args):
    if len(args) < 2:
        sys.exit(__doc__)
    n = int(args[0])
    for path in args[1:]:
        summarize(n, path)


if __name__ == "__main__":
    main(sys.argv[1:])
