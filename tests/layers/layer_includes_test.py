#!/usr/bin/python3
"""The layers of docs/architecture.md, checked on every #include of the repository's C++:
core/ includes nothing from kernels/ or scenarios/, kernels/ nothing from scenarios/, and no
scene family's folder includes another family's (only scenarios/common/ and the registry are
shared). Prints every include that points upward or sideways; exits 1 if there is any.

    layer_includes_test.py [--selftest]"""
import re
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
# Known exceptions, each with its reason; an entry that no longer occurs fails the check too
# (a stale exception hides the next one).
ALLOWED = {
    # The mixture study probes its states with the moduli family's element tests.
    ("scenarios/waves/scene_mixture_moduli.cpp", "scenarios/moduli/"),
    # The Python module is the front of the library API, as main.cpp is of the registry.
    ("scenarios/python/module.cpp", "scenarios/api/"),
}


def rank(path):
    top = path.split("/")[0]
    return {"core": 0, "kernels": 1, "scenarios": 2}.get(top)


def family(path):
    parts = path.split("/")
    if parts[0] != "scenarios" or len(parts) < 3 or parts[1] == "common":
        return None
    return parts[1]


def violations(root):
    found, used = [], set()
    for top in ("core", "kernels", "scenarios"):
        for f in sorted((root / top).rglob("*")):
            if f.suffix not in (".hpp", ".cpp", ".h"):
                continue
            rel = f.relative_to(root).as_posix()
            for inc in INCLUDE.findall(f.read_text(errors="replace")):
                r = rank(inc)
                if r is None:
                    continue
                fam, ifam = family(rel), family(inc)
                upward = r > rank(rel)
                sideways = fam is not None and ifam is not None and fam != ifam
                if not (upward or sideways):
                    continue
                allowed = next((a for a in ALLOWED if a[0] == rel and inc.startswith(a[1])), None)
                if allowed:
                    used.add(allowed)
                    continue
                found.append(f"{rel}: #include \"{inc}\" ({'upward' if upward else 'another family'})")
    for a in sorted(ALLOWED - used):
        found.append(f"stale exception: {a[0]} no longer includes {a[1]}*")
    return found


def selftest():
    """An upward include planted in a copy of the tree is reported."""
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        for top in ("core", "kernels", "scenarios/waves", "scenarios/moduli"):
            (t / top).mkdir(parents=True)
        (t / "core/a.hpp").write_text('#include "kernels/b.hpp"\n')
        (t / "kernels/b.hpp").write_text('#include "core/a.hpp"\n')
        (t / "scenarios/waves/scene_mixture_moduli.cpp").write_text('#include "scenarios/moduli/x.hpp"\n')
        (t / "scenarios/waves/c.cpp").write_text('#include "scenarios/moduli/x.hpp"\n')
        got = violations(t)
        assert any("core/a.hpp" in g and "upward" in g for g in got), got
        assert any("scenarios/waves/c.cpp" in g and "another family" in g for g in got), got
        assert not any(g.startswith("kernels/b.hpp:") for g in got), got
        assert not any(g.startswith("scenarios/waves/scene_mixture_moduli") for g in got), got
    print("selftest: planted upward and sideways includes reported, allowed ones not")


def main():
    if "--selftest" in sys.argv:
        selftest()
    found = violations(ROOT)
    for v in found:
        print(v)
    if found:
        sys.exit(1)
    print("layers: no include points upward or into another scene family")


if __name__ == "__main__":
    main()
