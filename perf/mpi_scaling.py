#!/usr/bin/python3
"""Strong scaling of a chain ensemble over MPI ranks on this machine: the same scene
(perf/mpi_chain_scaling.toml) as one process with 1 and with all threads, and as R ranks of
one thread, repetitions interleaved; medians of whole-process wall time, speed-up against
one rank of one thread, and a check that every run wrote the same results (bit for bit).

  perf/mpi_scaling.py [--reps N] [--ranks 1,2] [--out perf/results/mpi_scaling.json]
"""
import argparse
import json
import os
import pathlib
import platform
import shutil
import statistics
import subprocess
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parent.parent


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--ranks", default="1,2")
    ap.add_argument("--scene", default=str(REPO / "perf" / "mpi_chain_scaling.toml"))
    ap.add_argument("--out", default=str(REPO / "perf" / "results" / "mpi_scaling.json"))
    a = ap.parse_args()
    granular = str(REPO / "build" / "bin" / "granular")
    cores = os.cpu_count()
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_btl_vader_single_copy_mechanism="none")
    configs = [("1 process, 1 thread", 0, 1), ("1 process, %d threads" % cores, 0, cores)]
    configs += [("%d ranks x 1 thread" % r, r, 1) for r in map(int, a.ranks.split(",")) if r > 1]
    work = pathlib.Path(tempfile.mkdtemp(prefix="granular_scaling_"))
    times = {name: [] for name, _, _ in configs}
    try:
        for rep in range(a.reps):
            for name, ranks, threads in configs:
                out = work / ("%s_%d" % (name.replace(" ", "_").replace(",", ""), rep))
                cmd = [granular, "run", a.scene, "--out", str(out), "--quiet",
                       "--threads", str(threads)]
                if ranks:
                    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks)] + cmd
                t0 = time.perf_counter()
                subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
                times[name].append(time.perf_counter() - t0)
                print("rep %d %-22s %.2f s" % (rep + 1, name, times[name][-1]), flush=True)
        first = work / ("%s_0" % configs[0][0].replace(" ", "_").replace(",", ""))
        same = all(subprocess.run(
            ["/usr/bin/python3", str(REPO / "tests" / "mpi" / "compare_outputs.py"), str(first),
             str(d)], stdout=subprocess.DEVNULL).returncode == 0
            for d in work.iterdir() if d != first)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    base = statistics.median(times[configs[0][0]])
    rows = [{"configuration": n, "ranks": max(r, 1), "threads_per_rank": t,
             "wall_seconds": times[n], "median_seconds": statistics.median(times[n]),
             "speedup_vs_one_thread": base / statistics.median(times[n])}
            for n, r, t in configs]
    result = {"scene": os.path.relpath(a.scene, REPO), "machine": platform.node(),
              "cores": cores, "repetitions": a.reps, "same_results_bitwise": same,
              "runs": rows}
    pathlib.Path(a.out).write_text(json.dumps(result, indent=2) + "\n")
    for r in rows:
        print("%-22s median %.2f s  speed-up %.2f" % (r["configuration"], r["median_seconds"],
                                                       r["speedup_vs_one_thread"]))
    print("same results bit for bit:", same)


if __name__ == "__main__":
    main()
