#!/usr/bin/env python3
"""Runs a gtest binary's selected tests in one process and, after a test that ends the
process (a signal), goes on with the tests after it; prints the totals and every crashed test.

    gpu_suite_runner.py BINARY GTEST_FILTER LOG_FILE BUDGET_SECONDS"""
import subprocess, sys, time, re
binary, gfilter, out, budget = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
listing = subprocess.run([binary, "--gtest_list_tests", "--gtest_filter=" + gfilter],
                         capture_output=True, text=True).stdout
names, suite = [], None
for line in listing.splitlines():
    # "Suite.  # TypeParam = ..." opens a suite, "  Name  # GetParam() = ..." is a test;
    # anything else (a library's banner) is skipped.
    if re.match(r"^\S+\.(\s|$)", line):
        suite = line.split()[0]
    elif line.startswith("  ") and line.strip() and suite:
        names.append(suite + line.split()[0])
print(f"{len(names)} tests listed")
t0 = time.time()
crashed, passed, failed, skipped = [], 0, [], 0
todo = names
with open(out, "w") as log:
    while todo and time.time() - t0 < budget:
        r = subprocess.run([binary, "--gtest_filter=" + ":".join(todo)], capture_output=True,
                           text=True, timeout=max(10, budget - (time.time() - t0)))
        log.write(r.stdout + r.stderr + f"\n== exit {r.returncode}\n")
        done = re.findall(r"^\[\s+(OK|FAILED|SKIPPED)\s+\] (\S+) \(", r.stdout, re.M)
        for kind, name in done:
            if kind == "OK": passed += 1
            elif kind == "SKIPPED": skipped += 1
            else: failed.append(name)
        finished = {name for _, name in done}
        runs = re.findall(r"^\[ RUN      \] (\S+)", r.stdout, re.M)
        if r.returncode < 0 or (runs and runs[-1] not in finished):
            last = runs[-1] if runs else "?"
            crashed.append(f"{last} (exit {r.returncode})")
            k = todo.index(last) if last in todo else len(todo)
            todo = todo[k + 1:]
        else:
            todo = []
print(f"passed {passed}, failed {len(set(failed))}, skipped {skipped}, crashed {len(crashed)}, "
      f"not run {len(todo)}, {time.time() - t0:.0f} s")
for f in sorted(set(failed)): print("FAILED", f)
for c in crashed: print("CRASHED", c)
