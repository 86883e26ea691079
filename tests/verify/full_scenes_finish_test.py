#!/usr/bin/python3
"""tests/verify/full_scenes_finish.py against a stand-in engine (a script that sleeps, then
writes a summary whose run record says `complete`, or exits 1):

- each finished scene is recorded as soon as it ends, with its status and the commit its
  binary was built from (the run record's), and a failing one makes the runner exit 1;
- a runner stopped with SIGTERM stops the scene it is running: no engine is left behind
  without a parent, still writing into the work folder.

    full_scenes_finish_test.py"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RUNNER = HERE / "full_scenes_finish.py"

# argv: run SCENE --out DIR --threads N --quiet. Sleeps while a file named `hold` exists next
# to it, so that the test decides when it ends; `fail` in the scene's name exits 1.
ENGINE = r'''#!/usr/bin/python3
import json, os, sys, time
from pathlib import Path
out = Path(sys.argv[sys.argv.index("--out") + 1])
out.mkdir(parents=True, exist_ok=True)
(out / "pid").write_text(str(os.getpid()))
hold = Path(__file__).with_name("hold")
while hold.exists():
    time.sleep(0.05)
if "chain_tones" in sys.argv[2]:
    sys.exit("stand-in failure")
(out / "summary.json").write_text(json.dumps(
    {"run": {"status": "complete", "granular_commit": "0123456789abcdef-modified"}}))
'''


def check(cond, what):
    if not cond:
        sys.exit(f"FAILED: {what}")


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is gone for this purpose: it runs nothing
    stat = Path(f"/proc/{pid}/stat")
    return stat.exists() and stat.read_text().split()[2] != "Z"


def main():
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        engine = tmp / "engine"
        engine.write_text(ENGINE)
        engine.chmod(0o755)
        record = tmp / "times.md"
        work = tmp / "work"

        # Two scenes, the second failing: both recorded, exit 1.
        r = subprocess.run([sys.executable, str(RUNNER), str(engine), "--scenes",
                            "continuum_fit,chain_tones", "--threads", "1", "--work", str(work),
                            "--record", str(record)], capture_output=True, text=True, timeout=60)
        check(r.returncode == 1, f"a failing scene must make the runner exit 1: {r.stdout}")
        rows = [l for l in record.read_text().splitlines() if l.startswith("| 20")]
        check(len(rows) == 2, f"two rows recorded: {rows}")
        check(rows[0].split("|")[3].strip() == "continuum_fit" and
              rows[0].rstrip(" |").endswith("complete"), f"first row: {rows[0]}")
        check(rows[0].split("|")[2].strip() == "0123456-modified",
              f"the row must name the binary's commit from its run record: {rows[0]}")
        check("failed (exit 1)" in rows[1], f"second row: {rows[1]}")

        # SIGTERM while the first scene runs: the engine goes with the runner, and the row of
        # a scene that did not end is not written.
        (tmp / "hold").write_text("")
        record.unlink()
        # The first run's pid file would be read before the runner clears the folder for its
        # new run: remove it, so that the pid read below is the running engine's.
        shutil.rmtree(work / "continuum_fit")
        runner = subprocess.Popen([sys.executable, str(RUNNER), str(engine), "--scenes",
                                   "continuum_fit", "--threads", "1", "--work", str(work),
                                   "--record", str(record)], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        pid_file = work / "continuum_fit" / "pid"
        deadline = time.time() + 30
        while not pid_file.exists() and time.time() < deadline:
            time.sleep(0.05)
        check(pid_file.exists(), "the stand-in engine did not start")
        time.sleep(0.2)
        pid = int(pid_file.read_text())
        runner.send_signal(signal.SIGTERM)
        check(runner.wait(timeout=30) != 0, "a stopped runner must not exit 0")
        deadline = time.time() + 10
        while alive(pid) and time.time() < deadline:
            time.sleep(0.05)
        gone = not alive(pid)
        if not gone:
            os.kill(pid, signal.SIGKILL)
        check(gone, "the runner's engine outlived the runner stopped with SIGTERM")
        check(not record.exists(), "a scene that did not end was recorded")
    print("full_scenes_finish: rows recorded as scenes end; SIGTERM stops the running scene")


if __name__ == "__main__":
    main()
