#!/usr/bin/python3
"""Runs the full scene files to their end and records each one's wall time: every full scene
must finish on the current code (exit 0, a summary.json whose run record says `complete`).
The scenes whose references verify_references.py reruns (its fast and full sets) are left to
it; the rest are run here.

    full_scenes_finish.py GRANULAR [--scenes a,b,...] [--threads N] [--work DIR]
                          [--record FILE] [--list]

--record appends one row per run to a Markdown table in FILE (date, the commit the binary was
built from as its run record names it, scene, threads, wall time, status), the file that keeps the wall times of these runs
(scenarios/reference/full_scene_times.md). Exits 1 when any run failed or did not finish.
The `long` label of ctest runs it (hours: the moduli studies take tens of minutes each).
"""
import argparse
import json
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))
sys.dont_write_bytecode = True
import verify_references  # noqa: E402  (its scene sets)


def full_scenes():
    """Scene files under scenarios/ that are not quick variants, by name."""
    names = sorted(p.stem for p in ROOT.glob("scenarios/*/*.toml")
                   if not p.stem.endswith("_quick") and not p.name.startswith("."))
    covered = set(verify_references.FAST) | set(verify_references.FULL)
    return [n for n in names if n not in covered]


def commit():
    try:
        return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def run(granular, name, threads, work):
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    start = time.time()
    proc = subprocess.run([granular, "run", str(verify_references.scene_file(name).relative_to(
        ROOT)), "--out", str(out), "--threads", str(threads), "--quiet"], cwd=ROOT,
        capture_output=True, text=True)
    seconds = time.time() - start
    status = "failed (exit %d): %s" % (proc.returncode, (proc.stderr.strip().splitlines()
                                                          or ["no message"])[-1])
    built_from = None
    if proc.returncode == 0:
        summary = out / "summary.json"
        if not summary.exists():
            status = "no summary.json (stopped before its end)"
        else:
            record = json.loads(summary.read_text()).get("run", {})
            status = record.get("status", "no run record")
            built_from = record.get("granular_commit")
    return seconds, status, built_from


def short_commit(full):
    """`abcdef1...-modified` as `abcdef1-modified`: the commit the binary was built from."""
    rev, _, rest = full.partition("-")
    return rev[:7] + ("-" + rest if rest else "")


def record(path, name, threads, seconds, status, built_from=None):
    if not path.exists():
        path.write_text(
            "# Wall times of the full scenes\n\n"
            "Appended by `tests/verify/full_scenes_finish.py --record` (`ctest -L long`): each\n"
            "run of a full scene to its end on the current code, on the machine named in the\n"
            "run's own record.\n\n"
            "| date (UTC) | commit | scene | threads | minutes | status |\n"
            "|---|---|---|---|---|---|\n")
    day = time.strftime("%Y-%m-%d", time.gmtime())
    with path.open("a") as f:
        # The binary's own commit (its run record) where it has one: the tree may have moved
        # on during a study of hours.
        rev = short_commit(built_from) if built_from else commit()
        f.write(f"| {day} | {rev} | {name} | {threads} | {seconds / 60:.1f} | {status} |\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("granular")
    ap.add_argument("--scenes", default="")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--work", default="")
    ap.add_argument("--record", default="")
    ap.add_argument("--list", action="store_true", help="print the scenes and stop")
    args = ap.parse_args()
    names = [s for s in args.scenes.split(",") if s] or full_scenes()
    if args.list:
        print("\n".join(names))
        return
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="granular_full_"))
    work.mkdir(parents=True, exist_ok=True)
    # A runner stopped with SIGTERM stops its scene too (subprocess.run kills the child on
    # the exception), instead of leaving it running for hours without a parent.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    failed = 0
    print(f"{'scene':34s} {'threads':>7s} {'minutes':>8s}  status", flush=True)
    for name in names:
        seconds, status, built_from = run(args.granular, name, args.threads, work)
        failed += status != "complete"
        print(f"{name:34s} {args.threads:7d} {seconds / 60:8.1f}  {status}", flush=True)
        if args.record:  # row by row: a study of hours is kept even if a later one is stopped
            record(Path(args.record), name, args.threads, seconds, status, built_from)
    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
