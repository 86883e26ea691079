#!/usr/bin/python3
"""scripts/seed_spread.py on chain_tones_quick with three seeds: the packings differ, the
scene file is left as it was, and every reported mean and standard error equals the one
computed here from the three runs' own summary.json; a chart's points are those means and
errors, index by index, and its PNG is written and listed; a seed whose run fails is listed,
left out of the statistics, and makes the script exit 1.

    seed_spread_test.py GRANULAR"""
import importlib.util
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "chains" / "chain_tones_quick.toml"


def check(cond, what):
    if not cond:
        sys.exit(f"FAILED: {what}")


def main():
    granular = sys.argv[1]
    before = SCENE.read_text()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "spread"
        cmd = [sys.executable, str(ROOT / "scripts" / "seed_spread.py"), granular, str(SCENE),
               "--seed-key", "disorder.seed", "--seeds", "1,2,3", "--out", str(out),
               "--threads", "1", "--quantities", "*band*"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        check(r.returncode == 0, f"script failed: {r.stdout[-800:]}{r.stderr[-800:]}")
        check(SCENE.read_text() == before, "the scene file was changed")
        check(not list(SCENE.parent.glob(".chain_tones_quick_seed_*")), "a seed copy was left")
        spread = json.loads((out / "spread.json").read_text())
        check(spread["seeds"] == [1, 2, 3] and spread["failed"] == {}, "seeds listed")
        summaries = [json.loads((out / f"seed_{k}" / "summary.json").read_text()) for k in (1, 2, 3)]
        check(summaries[0] != summaries[1], "two seeds gave the same summary")
        moved = 0
        for path, q in spread["quantities"].items():
            vals = q["values"]
            check(len(vals) == 3 and q["n"] == 3, f"{path}: three values")
            m = sum(vals) / 3
            se = math.sqrt(sum((v - m) ** 2 for v in vals) / 2 / 3)
            check(abs(q["mean"] - m) <= 1e-12 * max(1.0, abs(m)), f"{path}: mean")
            check(abs(q["standard_error"] - se) <= 1e-12 * max(1.0, se), f"{path}: s.e.")
            moved += se > 0
        check(moved > 10, f"only {moved} quantities vary between seeds")
        md = (out / "spread.md").read_text()
        check("| quantity | mean ± s.e. | values |" in md and "band" in md, "spread.md table")
        # Charts: points against the spread, then the PNG from the runs kept (--reuse).
        spec = importlib.util.spec_from_file_location("seed_spread", ROOT / "scripts" / "seed_spread.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        q = spread["quantities"]
        listed = sorted(p for p in q if "[0]" in p and p.replace("[0]", "[1]", 1) in q)
        check(len(listed) >= 2, "list quantities to chart")
        x_pat, y_pat = listed[0].replace("[0]", "[*]", 1), listed[1].replace("[0]", "[*]", 1)
        pts = mod.chart_points(q, x_pat, y_pat)
        check(len(pts) >= 2, f"chart points of {x_pat}:{y_pat}")
        for i, (x, y, e) in enumerate(pts):
            xp, yp = x_pat.replace("[*]", f"[{i}]"), y_pat.replace("[*]", f"[{i}]")
            check((x, y, e) == (q[xp]["mean"], q[yp]["mean"], q[yp]["standard_error"]),
                  f"chart point {i}")
        again = cmd + ["--reuse", "--chart", f"{x_pat}:{y_pat}"]
        r = subprocess.run(again, capture_output=True, text=True)
        check(r.returncode == 0 and "reused" in r.stdout, f"chart run: {r.stdout[-400:]}{r.stderr[-400:]}")
        png = out / "spread_1.png"
        check(png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "chart PNG written")
        check("(spread_1.png)" in (out / "spread.md").read_text(), "chart listed in spread.md")
        # A failing seed (one beyond 64 bits is refused by the scene file's reader) is listed
        # and left out.
        huge = "99999999999999999999"
        bad = cmd[:]
        bad[bad.index("1,2,3")] = "1," + huge
        bad[bad.index(str(out))] = str(Path(tmp) / "bad")
        r = subprocess.run(bad, capture_output=True, text=True)
        check(r.returncode == 1, f"a failed seed must exit 1, got {r.returncode}")
        failed = json.loads((Path(tmp) / "bad" / "spread.json").read_text())
        check(failed["seeds"] == [1] and huge in failed["failed"], "failed seed listed")
        check(f"Seed {huge} did not finish" in (Path(tmp) / "bad" / "spread.md").read_text(),
              "failed seed in spread.md")
    print("seed spread: statistics, seed copies and failures as documented")


if __name__ == "__main__":
    main()
