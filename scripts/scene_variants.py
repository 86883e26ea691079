#!/usr/bin/python3
"""Runs one scene file with keys changed per variant and tabulates chosen summary numbers side
by side: a parameter study from the command line (the column and pulse lengths of the wave
scene, docs in docs/guide_waves.md).

    scripts/scene_variants.py GRANULAR SCENE.toml --variant NAME:table.key=VALUE[;table.key=VALUE]
                              [--variant ...] --out DIR [--threads N] [--quantities PATTERN,...]
                              [--reuse] [--chart X:Y [--chart ...]] [--hline VALUE:LABEL]

Each variant runs a copy of the scene file beside the original (relative input paths keep their
meaning) with its keys set (a key absent from its table is added at the table's top; VALUE is
TOML: 48.0, [0.2, 0.5], "span"); the copy is removed afterwards. A key can be dropped with
table.key=-  (its default applies). Writes DIR/<name>/ (each run's outputs), DIR/variants.json
(every numeric summary path per variant) and DIR/variants.md (the paths matching --quantities,
fnmatch patterns, one column per variant). A variant whose run fails is listed with its message;
the script then exits 1. --reuse takes a variant's earlier run in DIR/<name>/ instead.

--chart draws Y against X over the variants into DIR/variants_<k>.png: X is a summary path,
Y an fnmatch pattern of summary paths, one curve per matching path (points sorted by X), e.g.
`preparation.volume_fraction_box:models.*.max_force`; --hline adds a horizontal line at VALUE
(a measured point) with its LABEL.
"""
import argparse
import fnmatch
import json
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from seed_spread import flatten, run_copy, with_key  # noqa: E402  (one rule for both scripts)


def parse_variant(spec):
    name, _, changes = spec.partition(":")
    if not name or not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise SystemExit(f"--variant {spec}: NAME (letters, digits, _ . -) before ':'")
    keys = []
    for change in [c for c in changes.split(";") if c.strip()]:
        path, eq, value = change.partition("=")
        table, _, key = path.strip().rpartition(".")
        if not eq or not table:
            raise SystemExit(f"--variant {spec}: each change is table.key=VALUE")
        value = value.strip()
        keys.append((table, key, None if value == "-" else value))
    return name, keys


def draw(path, runs, names, x_path, y_pat, hline):
    """Y against X over the variants, one curve per summary path matching y_pat."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ys = sorted({p for n in names for p in runs[n] if fnmatch.fnmatch(p, y_pat)})
    for y in ys:
        pts = sorted((runs[n][x_path], runs[n][y], n) for n in names
                     if isinstance(runs[n].get(x_path), (int, float))
                     and isinstance(runs[n].get(y), (int, float)))
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=y)
    if hline:
        value, _, label = hline.partition(":")
        ax.axhline(float(value), color="k", ls="--", lw=1, label=label or None)
    ax.set_xlabel(x_path)
    ax.set_ylabel(y_pat)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("granular")
    ap.add_argument("scene")
    ap.add_argument("--variant", action="append", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--quantities", default="*")
    ap.add_argument("--reuse", action="store_true")
    ap.add_argument("--chart", action="append", default=[])
    ap.add_argument("--hline")
    args = ap.parse_args()
    for spec in args.chart:
        if ":" not in spec:
            raise SystemExit(f"--chart {spec}: X:Y, two summary paths (Y may hold * and ?)")
    variants = [parse_variant(v) for v in args.variant]
    scene = Path(args.scene).resolve()
    text = scene.read_text()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    runs, failed = {}, {}
    for name, keys in variants:
        summary = out / name / "summary.json"
        if not (args.reuse and summary.exists()):
            changed = text
            for table, key, value in keys:
                changed = with_key(changed, table, key, value)
            error = run_copy(args.granular, scene, changed, f"variant_{name}", out / name,
                             args.threads)
            if error:
                failed[name] = error
                print(f"{name}: {error[0]}", flush=True)
                continue
        runs[name] = {}
        flatten(json.loads(summary.read_text()), "", runs[name])
        print(f"{name}: done", flush=True)
    names = [n for n, _ in variants if n in runs]
    (out / "variants.json").write_text(json.dumps(
        {"scene": str(args.scene), "variants": {n: [f"{t}.{k}={v}" for t, k, v in keys]
                                                for n, keys in variants},
         "failed": failed, "values": runs}, indent=1))
    patterns = [q for q in args.quantities.split(",") if q]
    paths = sorted({p for n in names for p in runs[n]})
    rows = [p for p in paths if any(fnmatch.fnmatch(p, q) for q in patterns)]
    md = [f"Variants of `{scene.name}`:\n"]
    for n, keys in variants:
        md.append(f"- `{n}`: " + (", ".join(f"`{t}.{k} = {'(default)' if v is None else v}`"
                                          for t, k, v in keys) or "as shipped"))
    for n, msg in failed.items():
        md.append(f"\nVariant {n} did not finish: {' '.join(msg)}")
    md += ["", "| quantity | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for p in rows:
        md.append(f"| `{p}` | " + " | ".join(
            f"{runs[n][p]:.4g}" if p in runs[n] else "" for n in names) + " |")
    for k, spec in enumerate(args.chart, 1):
        md.append(f"\n![{spec}](variants_{k}.png)")
        draw(out / f"variants_{k}.png", runs, names, *spec.split(":", 1), args.hline)
    (out / "variants.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
