#!/usr/bin/python3
"""The test binary removes its scratch paths when it ends (tests/test_main.cpp): run a few
tests that write into temp_dir / unique_temp_path folders, then no path named after the
binary's process id is left in the temporary directory. (Before, 619 such leftovers had piled
up there.)

    scratch_cleanup_test.py GRANULAR_TESTS"""
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main():
    binary = sys.argv[1]
    tmp = Path(tempfile.gettempdir())
    # ImpactScene.Shipped* leaves its output folder to the binary; the others remove their own.
    proc = subprocess.Popen([binary, "--gtest_filter=ImpactScene.ShippedGlassOnSteel*:"
                             "StateSnapshot.*:Xdmf.*:"
                             "NeighborListTest/0.DamagedListInACheckpointIsRefusedOnLoad",
                             "--kokkos-threads=1"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seen = set()
    # While it runs, note the scratch paths it makes (named ..._<pid>).
    while proc.poll() is None:
        seen |= {p.name for p in tmp.glob(f"granular_*_{proc.pid}")}
        time.sleep(0.01)
    out = proc.stdout.read()
    if proc.returncode != 0:
        sys.exit(f"FAILED: the tests themselves failed:\n{out[-2000:]}")
    if "[  PASSED  ] 5 tests" not in out:
        sys.exit(f"FAILED: expected 5 tests to run:\n{out[-2000:]}")
    left = sorted(p.name for p in tmp.glob(f"granular_*_{proc.pid}"))
    if left:
        sys.exit(f"FAILED: scratch paths left behind: {left}")
    print(f"scratch paths removed at the end ({len(seen)} seen while running)")


if __name__ == "__main__":
    main()
