#!/usr/bin/python3
"""Checks of a run spread over MPI ranks against the same run in one process (ctest drives
it; see tests/CMakeLists.txt). Usage:
  ensemble_test.py GRANULAR same SCENE RANKS [T]  R ranks give the files of one process
                                                  (of T threads; default 1)
  ensemble_test.py GRANULAR resume SCENE R1 R2    stopped on R1 ranks, resumed on R2
  ensemble_test.py GRANULAR fail SCENE            a failing rank stops every rank, no hang
  ensemble_test.py GRANULAR detects SCENE         the comparison sees another seed's run
SCENE is a file in tests/mpi/. Exit status 0 when the check holds."""
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
COMPARE = HERE / "compare_outputs.py"


def mpi_env():
    env = dict(os.environ)
    # Tests may run as root in containers; Open MPI refuses that unless told, and its
    # single-copy shared-memory path needs ptrace rights containers often lack.
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", OMP_PROC_BIND="false")
    return env


def run(granular, scene, out, ranks=0, extra=(), threads=None, timeout=600):
    """ranks 0: a plain process (no launcher); otherwise mpirun -np ranks."""
    cmd = [granular, "run", str(scene), "--out", str(out), "--quiet"]
    # One thread a process: the ranks share the test machine's cores (the engine's results
    # do not depend on the thread count; other tests check that).
    cmd += ["--threads", str(threads or 1)] + list(extra)
    if ranks:
        cmd = [os.environ.get("MPIEXEC", "mpirun"), "--oversubscribe", "--bind-to", "none", "-np", str(ranks)] + cmd
    p = subprocess.run(cmd, env=mpi_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True, timeout=timeout)
    return p.returncode, p.stdout


def same(a, b):
    p = subprocess.run(["/usr/bin/python3", str(COMPARE), str(a), str(b)],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    print(p.stdout.strip())
    return p.returncode == 0


def must(ok, what, log=""):
    if not ok:
        print("FAILED:", what)
        if log:
            print(log[-4000:])
        sys.exit(1)


def main():
    granular, check, scene = sys.argv[1], sys.argv[2], HERE / sys.argv[3]
    work = pathlib.Path(tempfile.mkdtemp(prefix="granular_mpi_"))
    try:
        one = work / "one"
        if check in ("same", "resume", "detects"):
            threads = int(sys.argv[5]) if check == "same" and len(sys.argv) > 5 else 1
            rc, log = run(granular, scene, one, threads=threads)
            must(rc == 0, "the run in one process", log)
        if check == "same":
            ranks = int(sys.argv[4])
            rc, log = run(granular, scene, work / "many", ranks)
            must(rc == 0, "the run on %d ranks" % ranks, log)
            must(same(one, work / "many"), "%d ranks wrote other files than one process" % ranks)
        elif check == "resume":
            r1, r2 = int(sys.argv[4]), int(sys.argv[5])
            out = work / "resumed"
            rc, log = run(granular, scene, out, r1, ["--stop-after-minutes", "0.0001"])
            must(rc == 0, "the interrupted run on %d ranks" % r1, log)
            must(not (out / "summary.json").exists() and not (out / "results.h5").exists(),
                 "an interrupted run left files that look finished")
            must(any((out / "variants").iterdir()), "the interrupted run left no checkpoint")
            rc, log = run(granular, scene, out, r2, ["--resume"])
            must(rc == 0, "the run resumed on %d ranks" % r2, log)
            must(same(one, out), "stopped on %d ranks and resumed on %d: other files" % (r1, r2))
        elif check == "detects":
            other = work / "other_scene.toml"
            text = scene.read_text().replace("\nseed = 1\n", "\nseed = 7\n", 1)
            must(text != scene.read_text(), "the scene has no seed to change")
            other.write_text(text)
            rc, log = run(granular, other, work / "other", 2)
            must(rc == 0, "the run with another seed", log)
            must(not same(one, work / "other"), "the comparison missed a run with another seed")
        elif check == "fail":
            out = work / "failed"
            try:
                rc, log = run(granular, scene, out, 2, timeout=120)
            except subprocess.TimeoutExpired:
                must(False, "a failing rank left the others waiting (no exit in 120 s)")
            print(log.strip()[:2000])
            must(rc != 0, "the run with a failing rank exited with status 0", log)
            must("rank 1: stopped: box edge" in log, "rank 1's own message is not shown", log)
            must(not (out / "summary.json").exists() and not (out / "results.h5").exists(),
                 "a failed run left files that look finished")
        else:
            must(False, "unknown check " + check)
        print("passed:", check, sys.argv[3:])
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
