#!/usr/bin/python3
"""Runs one scene over several packings (seeds) and reports every summary number as
mean +- standard error over them: figures of one realization (wave speeds, Q, exponents)
quoted with their spread.

    scripts/seed_spread.py GRANULAR SCENE.toml --seed-key column.seed --seeds 1,2,3,4,5
                           --out DIR [--threads N] [--quantities PATTERN,...] [--reuse]
                           [--chart X:Y[;X:Y...]]

Each seed runs a copy of the scene file, beside the original (relative input paths keep
their meaning), with `<table>.<key>` set to the seed; the copy is removed afterwards. Writes
DIR/seed_<k>/ (each run's outputs), DIR/spread.json (for every numeric summary path: values,
mean, standard error, n) and DIR/spread.md (the paths matching --quantities, fnmatch patterns;
default every path). A seed whose run fails is listed with its message and left out of the
statistics; the script exits 1 when any failed. --reuse takes a seed's earlier run in
DIR/seed_<k>/ (its summary.json) instead of running it again.

--chart draws each Y against X with error bars (mean +- standard error) into
DIR/spread_<k>.png: X and Y are summary paths with one `[*]` for the list index, e.g.
`fits[*].soft_fraction:fits[*].fit_M.exponent`; X is the mean over seeds (a list of the
same values in every run, such as the pressures or fractions of the table).
"""
import argparse
import fnmatch
import json
import math
import re
import subprocess
import sys
from pathlib import Path

SKIPPED = ("run.", "parameters.", "scene_file")


def flatten(value, at, out):
    if isinstance(value, dict):
        for k, v in value.items():
            flatten(v, f"{at}.{k}" if at else k, out)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            flatten(v, f"{at}[{i}]", out)
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        if math.isfinite(value) and not at.startswith(SKIPPED) and "seconds" not in at:
            out[at] = float(value)


def with_key(text, table, key, value):
    """The scene text with key = value inside [table] (added at the table's top if absent;
    removed where value is None)."""
    lines = text.splitlines()
    head = re.compile(r"^\s*\[([^\]]+)\]")
    inside, start = False, None
    for i, line in enumerate(lines):
        m = head.match(line)
        if m:
            inside = m.group(1).strip() == table
            if inside:
                start = i
            continue
        if inside and re.match(rf"^\s*{re.escape(key)}\s*=", line):
            if value is None:
                del lines[i]
            else:
                lines[i] = f"{key} = {value}"
            return "\n".join(lines) + "\n"
    if start is None:
        raise SystemExit(f"the scene has no [{table}] table for {table}.{key}")
    if value is not None:
        lines.insert(start + 1, f"{key} = {value}")
    return "\n".join(lines) + "\n"


def with_seed(text, table, key, seed):
    """The scene text with key = seed inside [table] (added at the table's top if absent)."""
    return with_key(text, table, key, seed)


def run_copy(granular, scene, text, tag, outdir, threads):
    """Runs `text` as a copy of `scene` beside it (relative input paths keep their meaning),
    into `outdir`; the copy is removed afterwards. Returns None, or [the failure's last line]."""
    copy = scene.with_name(f".{scene.stem}_{tag}.toml")
    copy.write_text(text)
    cmd = [granular, "run", str(copy), "--out", str(outdir), "--quiet"]
    if threads:
        cmd += ["--threads", str(threads)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    finally:
        copy.unlink()
    if proc.returncode == 0:
        return None
    last = (proc.stderr.strip() or proc.stdout.strip()).splitlines()[-1:]
    return [f"exit {proc.returncode}: " + " ".join(last)]


def mean_se(values):
    n = len(values)
    m = sum(values) / n
    if n < 2:
        return m, float("nan")
    var = sum((v - m) ** 2 for v in values) / (n - 1)
    return m, math.sqrt(var / n)


def chart_points(spread, x_pat, y_pat):
    """(x mean, y mean, y standard error) for every index i where both paths, with [*]
    replaced by [i], are in the spread."""
    if x_pat.count("[*]") != 1 or y_pat.count("[*]") != 1:
        raise SystemExit(f"--chart paths need one [*] each: {x_pat}:{y_pat}")
    points, i = [], 0
    while True:
        x, y = x_pat.replace("[*]", f"[{i}]"), y_pat.replace("[*]", f"[{i}]")
        if x not in spread and y not in spread:
            return points
        if x in spread and y in spread:
            points.append((spread[x]["mean"], spread[y]["mean"], spread[y]["standard_error"]))
        i += 1


def draw(path, points, x_pat, y_pat, n):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.2, 3.8))
    xs, ys, es = zip(*points)
    ax.errorbar(xs, ys, yerr=[0.0 if math.isnan(e) else e for e in es], fmt="o-", capsize=4,
                label=f"mean ± standard error over {n} packings")
    ax.set_xlabel(x_pat.replace("[*]", ""))
    ax.set_ylabel(y_pat.replace("[*]", ""))
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("granular")
    ap.add_argument("scene")
    ap.add_argument("--seed-key", required=True, help="<table>.<key> of the packing's seed")
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--out", required=True)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--quantities", default="*")
    ap.add_argument("--reuse", action="store_true", help="keep finished runs found in --out")
    ap.add_argument("--chart", default="", help="X:Y[;X:Y...] paths with [*] (see above)")
    args = ap.parse_args()
    table, _, key = args.seed_key.rpartition(".")
    if not table:
        raise SystemExit("--seed-key must be <table>.<key>")
    seeds = [int(s) for s in args.seeds.split(",") if s]
    scene = Path(args.scene).resolve()
    text = scene.read_text()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    runs, failed = {}, {}
    for seed in seeds:
        summary = out / f"seed_{seed}" / "summary.json"
        if args.reuse and summary.exists():
            runs[seed] = {}
            flatten(json.loads(summary.read_text()), "", runs[seed])
            print(f"seed {seed}: reused", flush=True)
            continue
        error = run_copy(args.granular, scene, with_seed(text, table, key, seed), f"seed_{seed}",
                         out / f"seed_{seed}", args.threads)
        if error:
            failed[seed] = error
            print(f"seed {seed}: {error[0]}", flush=True)
            continue
        values = {}
        flatten(json.loads((out / f"seed_{seed}" / "summary.json").read_text()), "", values)
        runs[seed] = values
        print(f"seed {seed}: done", flush=True)
    if not runs:
        sys.exit("no seed ran to its end")
    done = sorted(runs)
    paths = sorted(set.intersection(*(set(v) for v in runs.values())))
    spread = {}
    for p in paths:
        vals = [runs[s][p] for s in done]
        m, se = mean_se(vals)
        spread[p] = {"values": vals, "mean": m, "standard_error": se, "n": len(vals)}
    (out / "spread.json").write_text(json.dumps(
        {"scene": str(args.scene), "seed_key": args.seed_key, "seeds": done,
         "failed": {str(k): v for k, v in failed.items()}, "quantities": spread}, indent=1))
    patterns = [q for q in args.quantities.split(",") if q]
    rows = [p for p in paths if any(fnmatch.fnmatch(p, q) for q in patterns)]
    md = [f"Spread of `{scene.name}` over {len(done)} packings ({args.seed_key} = "
          f"{', '.join(map(str, done))}): mean ± standard error\n"]
    for seed, msg in failed.items():
        md.append(f"Seed {seed} did not finish: {' '.join(msg)}\n")
    md += ["| quantity | mean ± s.e. | values |", "|---|---|---|"]
    for p in rows:
        q = spread[p]
        md.append(f"| `{p}` | {q['mean']:.4g} ± {q['standard_error']:.2g} | "
                  + ", ".join(f"{v:.4g}" for v in q["values"]) + " |")
    charts = [c for c in args.chart.split(";") if c]
    for k, chart in enumerate(charts, 1):
        x_pat, _, y_pat = chart.partition(":")
        points = chart_points(spread, x_pat, y_pat)
        if not points:
            md.append(f"\nChart {k}: no quantity matches {chart}")
            continue
        draw(out / f"spread_{k}.png", points, x_pat, y_pat, len(done))
        md.append(f"\n![{y_pat} against {x_pat}](spread_{k}.png)")
    (out / "spread.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
