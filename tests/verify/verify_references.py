#!/usr/bin/python3
"""Reruns scenes and compares every number of their summary.json and every dataset of their
results.h5 with the committed reference in scenarios/reference/<scene>/. Every dataset of the
new results.h5 must carry a `unit` attribute, the same as the reference's where that has one.

    verify_references.py GRANULAR [--scenes a,b,...] [--set fast|slow|full|all] [--work DIR]

GRANULAR is the engine binary (build/bin/granular). Each scene runs with the thread count its
reference records (`run.threads`, one where none is recorded). A number is `same` when its
bits are equal, `within` when a reference folder's `tolerance.json` allows the difference
(`{"relative": {"<key or dataset pattern>": 1e-6}}`, fnmatch patterns on the paths printed
below), and `moved` otherwise. Prints one line per scene and every moved quantity (the
largest first), and exits 1 when anything moved or a run failed.

What is not compared: the run record (`run`: times, machine, threads), wall-clock figures
(`*seconds*`, `*per_second*`), paths that name the output folder, and charts.
"""
import argparse
import fnmatch
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = ROOT / "scenarios" / "reference"

# Scenes of a few seconds each: the default test suite verifies them.
FAST = ["two_particle_linear", "hysteretic_collision", "impact_glass_wall", "impact_benchmarks",
        "soft_collision", "lammps_forces", "signal_analysis_traces",
        "signal_analysis_synthetic", "chain_tones_quick", "chain_impulse_quick",
        "chain_master_equation_quick", "continuum_fit_quick"]
# Quick variants of a minute or more, and the full continuum_fit (half a minute; it fits the
# committed moduli references, so regenerating one of them must regenerate it too): the
# `verify` label (ctest -L verify).
SLOW = ["confined_compression_quick", "wave_transmission_quick",
        "wave_transmission_mixture_quick", "mixture_moduli_quick", "moduli_linear_quick",
        "moduli_tangential_stiffness_quick", "cohesion_list_quick", "reversibility_quick",
        "keep_friction_probes_quick", "jamming_friction_quick",
        "amplitude_sweep_friction_quick", "moduli_hertz_quick", "cohesive_sweep_quick",
        "system_size_quick", "continuum_fit"]
# Full scenes whose reference the current code reproduces, of minutes each: the
# `long` label (ctest -L long). A full scene joins this list once its reference is
# regenerated and verified.
FULL = ["wave_transmission", "confined_compression_hydrogel", "confined_compression_rubber",
        "isotropic_compression", "chain_tones", "chain_master_equation", "chain_impulse_exact",
        "chain_impulse", "chain_impulse_centre"]

SKIPPED_KEYS = ("seconds", "per_second", "started_utc", "finished_utc")


def scene_file(name):
    found = sorted(ROOT.glob(f"scenarios/*/{name}.toml"))
    if not found:
        raise SystemExit(f"no scene file scenarios/*/{name}.toml for reference {name}")
    return found[0]


def skipped(path):
    last = path.split(".")[-1]
    return path.startswith("run") or any(s in last for s in SKIPPED_KEYS)


def flatten_json(value, at, out):
    if isinstance(value, dict):
        for k, v in value.items():
            flatten_json(v, f"{at}.{k}" if at else k, out)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            flatten_json(v, f"{at}[{i}]", out)
    else:
        out[at] = value


def summary_numbers(path, out_dir):
    flat = {}
    flatten_json(json.loads(Path(path).read_text()), "", flat)
    result = {}
    for k, v in flat.items():
        if skipped(k):
            continue
        if isinstance(v, str) and out_dir and out_dir in v:
            continue  # a path inside the run's own output folder
        result[k] = v
    return result


def h5_datasets(path):
    import h5py
    import numpy as np
    out = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            data = obj[()]
            if isinstance(data, np.ndarray) and data.dtype.kind in "fiub":
                out["h5:/" + name] = data
    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return out


def h5_units(path):
    """'h5:/<dataset>' -> its `unit` attribute as text ('' where it has none)."""
    import h5py
    out = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            u = obj.attrs.get("unit", "")
            out["h5:/" + name] = u.decode() if isinstance(u, bytes) else str(u)
    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return out


def relative_difference(a, b):
    if isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, (int, float)) \
            or not isinstance(b, (int, float)):
        return None if a == b else math.inf
    if a == b or (math.isnan(a) and math.isnan(b)):
        return 0.0
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def compare(name, ref_dir, new_dir):
    """Returns (compared count, list of (path, reference, new, relative difference))."""
    import numpy as np
    tolerance = {}
    tol_file = ref_dir / "tolerance.json"
    if tol_file.exists():
        tolerance = json.loads(tol_file.read_text()).get("relative", {})

    def allowed(path):
        return max([t for p, t in tolerance.items() if fnmatch.fnmatch(path, p)], default=0.0)

    moved, within, count = [], [], 0
    old = summary_numbers(ref_dir / "summary.json", None)
    new = summary_numbers(new_dir / "summary.json", str(new_dir))
    for key in sorted(set(old) | set(new)):
        if isinstance(old.get(key), str) and "/" in old.get(key, "") and key not in new:
            continue  # a path in the reference's own output folder
        count += 1
        if key not in old or key not in new:
            moved.append((key, old.get(key, "(absent)"), new.get(key, "(absent)"), math.inf))
            continue
        d = relative_difference(old[key], new[key])
        if d is None:
            continue
        if d > allowed(key):
            moved.append((key, old[key], new[key], d))
        elif d > 0:
            within.append(key)
    if (ref_dir / "results.h5").exists():
        a = h5_datasets(ref_dir / "results.h5")
        b = h5_datasets(new_dir / "results.h5") if (new_dir / "results.h5").exists() else {}
        for key in sorted(set(a) | set(b)):
            count += 1
            if key not in a or key not in b:
                moved.append((key, "(present)" if key in a else "(absent)",
                              "(present)" if key in b else "(absent)", math.inf))
                continue
            x, y = a[key], b[key]
            if x.shape != y.shape:
                moved.append((key, f"shape {x.shape}", f"shape {y.shape}", math.inf))
                continue
            if np.array_equal(x, y, equal_nan=True):
                continue
            xf, yf = x.astype(float), y.astype(float)
            scale = np.maximum(np.maximum(np.abs(xf), np.abs(yf)), 1e-300)
            with np.errstate(invalid="ignore"):
                rel = np.where(np.isnan(xf) & np.isnan(yf), 0.0, np.abs(xf - yf) / scale)
            d = float(np.nanmax(rel)) if rel.size else 0.0
            if np.isnan(rel).any():
                d = math.inf
            if d > allowed(key):
                moved.append((key, f"{xf.size} values", f"largest change {d:.3g}", d))
            else:
                within.append(key)
    # Every dataset of a new results.h5 carries its unit (docs/data_formats.md), and the
    # reference's unit where the reference has one.
    ua = h5_units(ref_dir / "results.h5") if (ref_dir / "results.h5").exists() else {}
    ub = h5_units(new_dir / "results.h5") if (new_dir / "results.h5").exists() else {}
    for key in sorted(ub):
        if not ub[key]:
            moved.append((key + " unit", ua.get(key) or "(none)", "(none)", math.inf))
        elif ua.get(key) and ua[key] != ub[key]:  # references older than units have none
            moved.append((key + " unit", ua[key] or "(none)", ub[key], math.inf))
    return count, moved, within


def run_scene(granular, name, work):
    ref_dir = REFERENCE / name
    threads = 1
    try:
        threads = int(json.loads((ref_dir / "summary.json").read_text())["run"]["threads"])
    except (KeyError, ValueError, TypeError, json.JSONDecodeError):
        pass
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    start = time.time()
    proc = subprocess.run([granular, "run", str(scene_file(name).relative_to(ROOT)), "--out",
                           str(out), "--threads", str(threads), "--quiet"],
                          cwd=ROOT, capture_output=True, text=True)
    return proc, out, threads, time.time() - start


def selftest(granular, work):
    """The comparison must see one changed number in summary.json, one changed value in a
    dataset of results.h5 and one dataset whose unit is gone: a copy of a reference, altered,
    compared with a fresh run whose first dataset lost its unit."""
    import h5py
    name = "impact_glass_wall"
    proc, out, _, _ = run_scene(granular, name, work)
    if proc.returncode != 0:
        print("selftest: the run failed:", proc.stderr.strip()[-300:])
        return 1
    altered = work / "altered"
    shutil.copytree(REFERENCE / name, altered)
    summary = json.loads((altered / "summary.json").read_text())
    # The first non-zero real outside the parameters and the run record, changed by one
    # part in 1e12 in place.
    slots = []

    def walk(value, at):
        items = value.items() if isinstance(value, dict) else enumerate(value) \
            if isinstance(value, list) else []
        for k, v in items:
            path = (f"{at}.{k}" if at else k) if isinstance(value, dict) else f"{at}[{k}]"
            if isinstance(v, float) and v != 0 and not skipped(path) \
                    and not path.startswith("parameters"):
                slots.append((path, value, k))
            walk(v, path)
    walk(summary, "")
    key, container, index = slots[0]
    container[index] *= 1 + 1e-12
    (altered / "summary.json").write_text(json.dumps(summary))
    with h5py.File(altered / "results.h5", "r+") as f:
        names = []
        f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) and
                     o.dtype.kind == "f" and o.size > 0 else None)
        d = f[names[0]]
        data = d[()]
        data.flat[0] = data.flat[0] * (1 + 1e-12) if data.flat[0] != 0 else 1e-300
        d[...] = data
    with h5py.File(out / "results.h5", "r+") as f:
        if "unit" in f[names[0]].attrs:
            del f[names[0]].attrs["unit"]
    _, moved, _ = compare(name, altered, out)
    seen = {m[0] for m in moved}
    ok = key in seen and ("h5:/" + names[0]) in seen and \
        ("h5:/" + names[0] + " unit") in seen and len(moved) == 3
    print(f"selftest: changed {key} and h5:/{names[0]}, removed the unit of h5:/{names[0]}; "
          f"the comparison reported "
          f"{sorted(seen)}: {'passed' if ok else 'FAILED'}")
    return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("granular")
    ap.add_argument("--scenes", default="")
    ap.add_argument("--set", choices=["fast", "slow", "full", "all"], default="fast")
    ap.add_argument("--work", default="")
    ap.add_argument("--show", type=int, default=8, help="moved quantities shown per scene")
    ap.add_argument("--selftest", action="store_true",
                    help="check that an altered reference is reported, and nothing else")
    args = ap.parse_args()
    if args.selftest:
        work = Path(tempfile.mkdtemp(prefix="granular_verify_selftest_"))
        rc = selftest(args.granular, work)
        shutil.rmtree(work, ignore_errors=True)
        sys.exit(rc)
    names = [s for s in args.scenes.split(",") if s] or (
        {"fast": FAST, "slow": SLOW, "full": FULL, "all": FAST + SLOW + FULL}[args.set])
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="granular_verify_"))
    work.mkdir(parents=True, exist_ok=True)
    failed = 0
    print(f"{'scene':36s} {'threads':>7s} {'seconds':>8s} {'compared':>9s} {'moved':>6s}  largest")
    for name in names:
        proc, out, threads, seconds = run_scene(args.granular, name, work)
        if proc.returncode != 0:
            failed += 1
            print(f"{name:36s} {threads:7d} {seconds:8.1f}   run failed (exit {proc.returncode})")
            print("    " + (proc.stderr.strip().splitlines() or ["(no message)"])[-1])
            continue
        count, moved, within = compare(name, REFERENCE / name, out)
        largest = max((m[3] for m in moved), default=0.0)
        status = "same" if not moved and not within else (
            f"within tolerance ({len(within)})" if not moved else f"{largest:.3g}")
        print(f"{name:36s} {threads:7d} {seconds:8.1f} {count:9d} {len(moved):6d}  {status}")
        for path, a, b, d in sorted(moved, key=lambda m: -m[3])[:args.show]:
            print(f"    {path}: {a} -> {b}" + ("" if math.isinf(d) else f" (relative {d:.3g})"))
        failed += 1 if moved else 0
    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
