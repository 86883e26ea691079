#!/usr/bin/python3
"""perf/results/INDEX.md: every result file of perf/results/, grouped by benchmark, newest
first, each with the date and subject of the commit that added it (what was measured and
why), so a reader finds the latest figures without opening 140 files.

    results_index.py          rewrite INDEX.md
    results_index.py --check  exit 1 when INDEX.md misses a result file or lists one that is
                              gone (the check needs no git history: a shallow clone passes)
"""
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "perf" / "results"
INDEX = RESULTS / "INDEX.md"

GROUPS = [  # (title, pattern on the file name), first match wins
    ("Peer comparison with LAMMPS (perf/peer/)", r"^peer"),
    ("DEM throughput on a GPU", r"^dem_throughput_h\d+|^gpu_|^ncu_"),
    ("DEM throughput on the CPU", r"^dem_throughput"),
    ("Flatness of the force pass", r"^flatness"),
    ("MPI ensembles", r"^mpi_"),
    ("Energy drift against the time step", r"^dem_energy_vs_dt"),
    ("Mixed precision: accuracy, speed and memory", r"^mixed_precision"),
    ("Other", r""),
]


def added(path):
    """Date and subject of the first commit that added the file (none: not committed yet)."""
    out = subprocess.run(["git", "log", "--diff-filter=A", "--format=%cs\t%s", "--", str(path)],
                         cwd=ROOT, capture_output=True, text=True).stdout.strip().splitlines()
    if not out:
        return "", "(added with this index)"
    date, subject = out[-1].split("\t", 1)
    return date, subject


def render():
    files = sorted(p for p in RESULTS.iterdir() if p.is_file() and p.name != "INDEX.md")
    rows = {title: [] for title, _ in GROUPS}
    for f in files:
        title = next(t for t, pat in GROUPS if re.search(pat, f.name))
        date, subject = added(f.relative_to(ROOT))
        subject = subject if len(subject) <= 160 else subject[:157] + "..."
        rows[title].append((date, f.name, subject))
    out = ["# perf/results", "",
           "Every result file here, by benchmark, newest first: the date and subject of the",
           "commit that added it. `peer_latest.md` is the latest peer comparison. Written by",
           "`perf/results_index.py` (a test checks that it is up to date).", ""]
    for title, _ in GROUPS:
        if not rows[title]:
            continue
        out += ["## " + title, "", "| added | file | what was measured |", "|---|---|---|"]
        for date, name, subject in sorted(rows[title], key=lambda r: (r[0], r[1]), reverse=True):
            out.append("| %s | [%s](%s) | %s |" % (date, name, name, subject.replace("|", "/")))
        out.append("")
    return "\n".join(out)


def main():
    if "--check" in sys.argv:
        listed = set(re.findall(r"^\| [^|]* \| \[([^\]]+)\]", INDEX.read_text(), re.M)) \
            if INDEX.exists() else set()
        present = {p.name for p in RESULTS.iterdir() if p.is_file() and p.name != "INDEX.md"}
        missing, gone = sorted(present - listed), sorted(listed - present)
        for name in missing:
            print("not in perf/results/INDEX.md: " + name)
        for name in gone:
            print("listed in perf/results/INDEX.md but gone: " + name)
        if missing or gone:
            print("run perf/results_index.py")
            return 1
        print("perf/results/INDEX.md lists all %d result files" % len(present))
        return 0
    INDEX.write_text(render())
    return 0


if __name__ == "__main__":
    sys.exit(main())
