#!/usr/bin/python3
"""Markdown table of two bench_dem_throughput result files (before / after a change):
median particle-steps per second per physics switch and size, and their ratio.

    /usr/bin/python3 perf/compare_throughput.py BEFORE.json AFTER.json [BEFORE2.json AFTER2.json ...]

Files are taken in pairs (e.g. the 1-thread pair, then the 2-thread pair)."""
import json
import sys


def rows(path):
    with open(path) as f:
        data = json.load(f)
    return {(r["physics"], r["N"], r["threads"]): r for r in data["rows"]}


def main(paths):
    if len(paths) < 2 or len(paths) % 2:
        sys.exit(__doc__)
    print("| physics | N | threads | before (M/s) | after (M/s) | after / before | bytes/particle-step before → after |")
    print("|---|---|---|---|---|---|---|")
    for before_path, after_path in zip(paths[0::2], paths[1::2]):
        before, after = rows(before_path), rows(after_path)
        for key in after:
            if key not in before:
                continue
            b, a = before[key], after[key]
            mb, ma = b["median_particle_steps_per_s"] / 1e6, a["median_particle_steps_per_s"] / 1e6
            print(f"| {key[0]} | {key[1]} | {key[2]} | {mb:.2f} | {ma:.2f} | {ma / mb:.2f} | "
                  f"{b['bytes_per_particle_step']:.0f} → {a['bytes_per_particle_step']:.0f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
