#!/usr/bin/python3
"""scripts/scene_variants.py on chain_tones_quick: keys are replaced, added and dropped in their
own table only; every tabulated number is the run's own summary value; the scene file is left as
it was and no copy stays behind; a variant the engine refuses is listed and makes the script
exit 1.

    scene_variants_test.py GRANULAR"""
import importlib.util
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "chains" / "chain_tones_quick.toml"
SCRIPT = ROOT / "scripts" / "scene_variants.py"


def check(cond, what):
    if not cond:
        sys.exit(f"FAILED: {what}")


def main():
    granular = sys.argv[1]
    sys.path.insert(0, str(ROOT / "scripts"))
    spec = importlib.util.spec_from_file_location("seed_spread", ROOT / "scripts" / "seed_spread.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    text = "[a]\nx = 1\ny = 2\n\n[b]\nx = 3\n"
    check(mod.with_key(text, "b", "x", "[4, 5]") == "[a]\nx = 1\ny = 2\n\n[b]\nx = [4, 5]\n",
          "replaced in its own table only")
    check(mod.with_key(text, "a", "z", "7") == "[a]\nz = 7\nx = 1\ny = 2\n\n[b]\nx = 3\n",
          "added at the table's top")
    check(mod.with_key(text, "a", "y", None) == "[a]\nx = 1\n\n[b]\nx = 3\n", "dropped")
    try:
        mod.with_key(text, "c", "x", "1")
        check(False, "a missing table must stop the script")
    except SystemExit:
        pass
    before = SCENE.read_text()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "variants"
        cmd = [sys.executable, str(SCRIPT), granular, str(SCENE), "--variant",
               "one:disorder.seed=1", "--variant", "two:disorder.seed=2", "--variant",
               "bad:disorder.seed=\"x\"", "--out", str(out), "--threads", "1"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        check(r.returncode == 1, f"a refused variant must exit 1: {r.stdout[-600:]}{r.stderr[-600:]}")
        check(SCENE.read_text() == before, "the scene file was changed")
        check(not list(SCENE.parent.glob(".chain_tones_quick_variant_*")), "a copy was left")
        data = json.loads((out / "variants.json").read_text())
        check(set(data["values"]) == {"one", "two"} and "bad" in data["failed"], "variants listed")
        moved = 0
        for name in ("one", "two"):
            values = {}
            mod.flatten(json.loads((out / name / "summary.json").read_text()), "", values)
            check(values == data["values"][name], f"{name}: the table holds the run's numbers")
        one, two = data["values"]["one"], data["values"]["two"]
        moved = sum(one[p] != two[p] for p in one if p in two)
        check(moved > 10, f"only {moved} numbers differ between the two seeds")
        md = (out / "variants.md").read_text()
        check("| quantity | one | two |" in md and "Variant bad did not finish" in md, "variants.md")
    print("scene variants: keys changed in their tables, numbers from the runs, refusals listed")


if __name__ == "__main__":
    main()
