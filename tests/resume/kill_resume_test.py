#!/usr/bin/python3
"""Kills runs of a checkpointing scene with SIGKILL and continues them with --resume: the
resumed run must end with the outputs of an uninterrupted run, bit for bit, and no kill may
leave the output folder with a mixed or partial output set. ctest drives it (see
tests/CMakeLists.txt). Usage:

    kill_resume_test.py GRANULAR SCENE MODE [--ranks R] [--kills N] [--seed S]
                        [--no-kill-at REGEX] [--work DIR] [--keep]

SCENE is a scene file (tests/resume/*.toml); MODE is one of
  random   N kills at moments drawn from a generator seeded with S (the moments are fixed,
           what the run has reached by then depends on the machine's speed): each killed run
           is resumed, and the resumed run is killed again at a random moment, until a run
           finishes; then a new chain of runs starts, until N kills are done.
  commits  every run is stopped (SIGSTOP to each of its processes) as soon as inotify reports
           a commit (a rename into a final name) or a removal in the output folder, the
           folder is inspected, and the run is killed there when that file version (for a
           removal: that kind of file in that folder) has not been killed at yet, or when the
           folder is found wrong (to see what a resume makes of it); otherwise it goes on.
           A resumed run repeats the work since its checkpoint and is killed at the next
           version not killed at yet, so every commit of the run gets its kill. The stop
           lands a fraction of a millisecond after the event: two file operations closer
           together than that are seen, and killed at, as one.
--ranks R runs through mpiexec with R ranks. In random mode a resume then runs on R ranks or
in one plain process, and a kill hits the whole job, mpiexec alone (its ranks have process
groups of their own and go on until they notice) or one rank.
--no-kill-at leaves paths matching REGEX out of the kill points of commits mode (they are
still inspected at every stop).

Checked after every kill (and in commits mode at every stop):
  - a file under its final name is whole: HDF5 opens and reads, summary.json parses, a
    checkpoint index ends with its end line, a stage pointer holds a stage number; no file
    is written in place under its final name;
  - every file version is one the uninterrupted run also wrote (seen at each of its own
    commits), so a resume that diverges is caught at its first checkpoint, next to the kill
    that caused it;
  - files that refer to each other fit: an XDMF file names datasets its HDF5 file holds, with
    those shapes; a stage pointer names a stage whose files are all there and a finished
    unit's index has its HDF5 file (what a resume reads);
  - a summary.json (a folder that looks finished) comes with the whole output set of the
    uninterrupted run;
  - the record of the parts (run_parts.jsonl): a resumed run killed leaves the lines it
    found and at most its own, "interrupted" (written at its progress reports), and a run
    that ends by itself lists exactly the lines it found as its summary's earlier parts.
Every kill is followed by --resume, as a user does after any kill, also when the folder
already looks finished. A resume refused for want of a checkpoint (killed before the first
one, or after the run removed it) must leave the folder as it was; then a folder without
summary.json is started afresh, as a user would, and one with it ends its chain.
When a run of a chain finishes, its folder must equal the uninterrupted run's: summary.json
numbers (run record and wall-clock fields left out, verify_references.py's rule), every
dataset and attribute of every HDF5 file (compare_outputs.py's items), every other file, and
no file more. The one documented difference: a resumed run's snapshot series starts where it
resumed, so its frames must be the uninterrupted run's frames of the same steps, ending with
the same final frame. A chain whose resume fails is left there, and a new chain goes on past
that kill point.

Charts and report.html are left out (GRANULAR_PLOTS_DIR names an empty folder): they are not
results, and drawing them costs about a second of matplotlib per run."""
import argparse
import ctypes
import hashlib
import json
import os
import random
import re
import select
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.dont_write_bytecode = True  # the source tree may be read-only; it stays as it is
sys.path.insert(0, str(HERE.parent / "mpi"))
sys.path.insert(0, str(HERE.parent / "verify"))
import compare_outputs  # noqa: E402  (HDF5 items: type, shape and bytes, attributes)
import ensemble_test  # noqa: E402  (the environment Open MPI needs in containers)
import verify_references  # noqa: E402  (summary.json numbers without the run record)

# A snapshot series (snapshot_series.hpp) restarts where a resumed run resumed: compared
# frame by frame, not as one file; so is its H5MD twin, whose frames are rows by step.
SERIES = {"snapshots.h5": "snapshots.xdmf"}
# The records of a run's earlier parts (run_report.cpp): one JSON line per part, the running
# part's own line ("interrupted") rewritten at each progress report of a long study.
PARTS = "run_parts.jsonl"
H5MD_SERIES = {"snapshots.h5md"}


def h5md_frames(path):
    """step_<n> -> digest of the frame's rows (positions, velocities, forces, box, time)."""
    import h5py
    frames = {}
    with h5py.File(path, "r") as f:
        p = f["particles/all"]
        for k, step in enumerate(p["position/step"][()]):
            rows = [(p[e + "/value"][k].tobytes(), p[e + "/time"][k].tobytes())
                    for e in ("position", "velocity", "force", "box/edges")]
            frames["step_%d" % step] = digest(rows)
    return frames

# inotify(7)
IN_CLOSE_WRITE, IN_MOVED_FROM, IN_MOVED_TO = 0x8, 0x40, 0x80
IN_CREATE, IN_DELETE, IN_DELETE_SELF = 0x100, 0x200, 0x400
IN_Q_OVERFLOW, IN_IGNORED, IN_ISDIR = 0x4000, 0x8000, 0x40000000
WATCH_MASK = IN_CLOSE_WRITE | IN_MOVED_FROM | IN_MOVED_TO | IN_CREATE | IN_DELETE | \
    IN_DELETE_SELF


def hidden(name):
    # Partial files are ".<name>.partial" (core/io/output.cpp): never taken for results.
    return name.startswith(".")


class Watch:
    """inotify over an output folder and the folders created in it: the engine's commits
    (a rename into the final name), removals, and writes under a final name, as they happen.
    Polling would see two commits a millisecond apart as one."""

    def __init__(self, root):
        self.libc = ctypes.CDLL(None, use_errno=True)
        self.fd = self.libc.inotify_init1(os.O_NONBLOCK | os.O_CLOEXEC)
        if self.fd < 0:
            raise OSError(ctypes.get_errno(), "inotify_init1")
        self.root = str(root)
        self.dirs = {}
        self.add_tree(self.root, report=False)

    def close(self):
        os.close(self.fd)

    def add_tree(self, path, report):
        """Watches path and its subfolders; with report, files already in them (written
        before the watch could be set) count as commits."""
        events = []
        wd = self.libc.inotify_add_watch(self.fd, os.fsencode(path), WATCH_MASK)
        if wd < 0:
            return events  # removed again already
        self.dirs[wd] = path
        try:
            entries = sorted(os.scandir(path), key=lambda e: e.name)
        except OSError:
            return events
        for e in entries:
            if e.is_dir(follow_symlinks=False):
                events += self.add_tree(e.path, report)
            elif report and not hidden(e.name):
                events.append(("commit", os.path.relpath(e.path, self.root)))
        return events

    def read(self, timeout):
        """Events as (kind, path relative to the folder): commit, removal, in place."""
        events = []
        if not select.select([self.fd], [], [], timeout)[0]:
            return events
        while True:
            try:
                buf = os.read(self.fd, 1 << 16)
            except BlockingIOError:
                return events
            at = 0
            while at < len(buf):
                wd, mask, _, size = struct.unpack_from("iIII", buf, at)
                name = buf[at + 16:at + 16 + size].split(b"\0", 1)[0].decode()
                at += 16 + size
                if mask & IN_Q_OVERFLOW:
                    events.append(("overflow", ""))
                if mask & IN_IGNORED:
                    self.dirs.pop(wd, None)
                    continue
                folder = self.dirs.get(wd)
                if folder is None or not name:
                    continue
                path = os.path.join(folder, name)
                rel = os.path.relpath(path, self.root)
                if mask & IN_ISDIR:
                    if mask & (IN_CREATE | IN_MOVED_TO):
                        events += self.add_tree(path, report=True)
                    continue
                if hidden(name):
                    continue
                if mask & IN_MOVED_TO:
                    events.append(("commit", rel))
                elif mask & (IN_DELETE | IN_MOVED_FROM):
                    events.append(("removal", rel))
                elif mask & (IN_CREATE | IN_CLOSE_WRITE):
                    events.append(("in place", rel))


def proc_state(pid):
    """(state, SID) of a process, or None when it is gone."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            s = f.read()
    except OSError:
        return None
    rest = s[s.rindex(")") + 2:].split()
    return rest[0], int(rest[3])


def job_members(sid):
    """The live processes with this SID: a job's mpiexec and its ranks (setsid at start)."""
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            st = proc_state(int(d))
            if st is not None and st[1] == sid and st[0] not in "ZX":
                out.append(int(d))
    return out


class Engine:
    """One granular run (plain, or mpiexec with its ranks), started under setsid. Open MPI
    gives each rank a process group of its own, so the SID is what holds the whole job."""

    def __init__(self, cmd, env, log_path, launcher):
        self.cmd = cmd
        self.log_path = log_path
        self.launcher = launcher  # mpiexec: ranks to find; else the one process
        with open(log_path, "wb") as log:
            self.p = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT,
                                      start_new_session=True)
        self.started = time.monotonic()
        self.stopped_for = 0.0  # seconds spent stopped for inspection

    def members(self):
        if self.launcher:
            return job_members(self.p.pid)
        st = proc_state(self.p.pid)
        return [self.p.pid] if st is not None and st[0] not in "ZX" else []

    def finished(self):
        return self.p.poll() is not None and not self.members()

    def signal_all(self, sig):
        pids = self.members()
        for pid in pids:
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass
        return pids

    def stop(self):
        """SIGSTOP to every process of the job; returns once all of them are stopped, so the
        folder holds what a kill at this moment would leave."""
        self.stop_began = time.monotonic()
        deadline = self.stop_began + 10
        while time.monotonic() < deadline:
            pids = self.signal_all(signal.SIGSTOP)
            states = [proc_state(pid) for pid in pids]
            if all(st is None or st[0] in "TtZX" for st in states):
                return
            time.sleep(0.0002)
        raise RuntimeError("the run did not stop within 10 s")

    def cont(self):
        self.signal_all(signal.SIGCONT)
        self.stopped_for += time.monotonic() - self.stop_began

    def active_seconds(self):
        return time.monotonic() - self.started - self.stopped_for

    def wait_gone(self, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.finished():
                return True
            time.sleep(0.01)
        return False

    def kill(self, how="job", rng=None):
        """SIGKILL: 'job' every process at once; 'mpiexec' mpiexec's process group (the ranks
        lose their launcher); 'rank' one rank (mpiexec then ends the others). Returns a note
        when the job did not end by itself within 30 s (then everything is killed)."""
        note = ""
        if how == "mpiexec":
            os.killpg(self.p.pid, signal.SIGKILL)
        elif how == "rank":
            ranks = sorted(pid for pid in self.members() if pid != self.p.pid)
            os.kill(rng.choice(ranks) if ranks else self.p.pid, signal.SIGKILL)
        if how != "job" and not self.wait_gone(30):
            note = "the job did not end within 30 s after %s was killed" % how
        while not self.finished():
            self.signal_all(signal.SIGKILL)
            time.sleep(0.005)
        self.p.wait()
        return note

    def log_tail(self, chars=3000):
        try:
            return Path(self.log_path).read_text(errors="replace")[-chars:]
        except OSError:
            return ""


def digest(value):
    return hashlib.sha1(repr(value).encode()).hexdigest()[:16]


class Content:
    """One version of one file: a digest of what it says (HDF5 items, summary numbers, text)
    and what is needed to judge it."""

    def __init__(self, rel, path, out_dir):
        self.rel, self.error, self.items, self.numbers = rel, None, None, None
        self.parts = None
        self.refs, self.shapes, self.frames = [], {}, None
        name = os.path.basename(rel)
        try:
            if name.endswith(".h5") or name in H5MD_SERIES:
                self.read_h5(path)
            elif name == PARTS:
                # Run records with wall times: read whole, line by line, never compared as a
                # result (parts_checks judges them).
                self.parts = [json.loads(l) for l in Path(path).read_text().splitlines() if l]
                self.digest = "run record"
            elif name == "summary.json":
                json.loads(Path(path).read_text())  # refused when cut short
                self.numbers = verify_references.summary_numbers(path, out_dir)
                self.digest = digest(sorted(self.numbers.items()))
            else:
                text = Path(path).read_bytes().decode(errors="replace").replace(out_dir, "<out>")
                self.digest = digest(text)
                self.check_text(name, text)
        except Exception as e:  # any failure to read is the finding
            self.error = "%s: %s" % (type(e).__name__, str(e).splitlines()[0] if str(e) else "")
            self.digest = "unreadable"

    def read_h5(self, path):
        items = compare_outputs.h5_items(path)
        self.items = {k: v for k, v in items.items()
                      if not (k.startswith("attr") and ("seconds" in k or "per_second" in k))}
        self.digest = digest(sorted(self.items.items()))
        for k, v in self.items.items():
            if k.startswith("data "):
                self.shapes[k[5:]] = tuple(v[1])
        if os.path.basename(path) in SERIES:
            groups = {}
            for k, v in self.items.items():
                name = k[5:] if k.startswith("data ") else k[5:].split("@")[0]
                groups.setdefault(name.strip("/").split("/")[0], []).append((k, v))
            self.frames = {g: digest(sorted(v)) for g, v in groups.items() if g}
        elif os.path.basename(path) in H5MD_SERIES:
            self.frames = h5md_frames(path)

    def check_text(self, name, text):
        if name.endswith(".xdmf"):
            root = ET.fromstring(text)
            for item in root.iter("DataItem"):
                if item.get("Format") == "HDF":
                    h5, _, dataset = item.text.strip().partition(":")
                    dims = tuple(int(d) for d in item.get("Dimensions").split())
                    self.refs.append((h5, dataset.lstrip("/"), dims))
        elif name.endswith(".index"):
            # save_moduli_part: the last line counts the entry lines; without it the index
            # was cut short.
            lines = text.splitlines()
            if not lines or not re.fullmatch(r"end \d+", lines[-1]) or \
                    int(lines[-1].split()[1]) != len(lines) - 2:
                raise ValueError("no end line counting its entries")
        elif name.endswith("_stage"):
            int(text)  # the number of the last finished stage


def list_files(folder):
    out = {}
    for d, dirs, files in os.walk(folder):
        dirs[:] = [x for x in dirs if not hidden(x)]
        for f in files:
            if not hidden(f):
                p = os.path.join(d, f)
                try:
                    out[os.path.relpath(p, folder)] = os.stat(p)
                except FileNotFoundError:
                    pass
    return out


def partial_files(folder):
    return sorted(os.path.relpath(os.path.join(d, f), folder)
                  for d, _, files in os.walk(folder) for f in files if hidden(f))


class Folder:
    """The files of an output folder, each read once per version (a rename into place gives
    a new inode)."""

    def __init__(self, path):
        self.path = str(path)
        self.cache = {}

    def contents(self):
        out = {}
        for rel, st in list_files(self.path).items():
            key = (rel, st.st_ino, st.st_mtime_ns, st.st_size)
            if key not in self.cache:
                self.cache[key] = Content(rel, os.path.join(self.path, rel), self.path)
            out[rel] = self.cache[key]
        return out


def show(v):
    if isinstance(v, tuple) and len(v) == 3 and isinstance(v[2], bytes):
        dtype, shape, raw = v
        if dtype in ("float64", "int32", "int64") and raw:
            import numpy as np
            a = np.frombuffer(raw, dtype=dtype)
            return "%s %s [%s%s]" % (dtype, shape, " ".join(repr(x) for x in a[:4]),
                                     " ..." if a.size > 4 else "")
        return "%s %s" % (dtype, shape)
    return repr(v)[:120]


def differences(a, b, limit=6):
    """What differs between two versions of a file (a: the uninterrupted run's)."""
    if a.items is not None and b.items is not None:
        keys = sorted(k for k in set(a.items) | set(b.items)
                      if a.items.get(k, None) is None or b.items.get(k, None) is None
                      or digest(a.items[k]) != digest(b.items[k]))
        out = []
        for k in keys[:limit]:
            va, vb = a.items.get(k), b.items.get(k)
            line = "%s: %s -> %s" % (k, "(absent)" if va is None else show(va),
                                     "(absent)" if vb is None else show(vb))
            if va is not None and vb is not None and isinstance(va, tuple) and \
                    va[0] == vb[0] == "float64" and va[1] == vb[1]:
                import numpy as np
                x, y = np.frombuffer(va[2], "float64"), np.frombuffer(vb[2], "float64")
                bad = np.flatnonzero((x != y) & ~(np.isnan(x) & np.isnan(y)))
                if bad.size:
                    line += "; %d values differ, first at [%d]: %r -> %r" % (
                        bad.size, bad[0], x[bad[0]], y[bad[0]])
            out.append(line)
        return out + (["... %d more" % (len(keys) - limit)] if len(keys) > limit else [])
    if a.numbers is not None and b.numbers is not None:
        keys = sorted(k for k in set(a.numbers) | set(b.numbers)
                      if repr(a.numbers.get(k, "(absent)")) != repr(b.numbers.get(k, "(absent)")))
        return ["%s: %r -> %r" % (k, a.numbers.get(k, "(absent)"), b.numbers.get(k, "(absent)"))
                for k in keys[:limit]] + (["... %d more" % (len(keys) - limit)]
                                           if len(keys) > limit else [])
    return ["contents differ"]


def closest(versions, c):
    """The version with the fewest items unlike c's (the checkpoint of the same step)."""
    def unlike(v):
        if v.items is None or c.items is None:
            return 0
        return sum(1 for k in set(v.items) | set(c.items)
                   if k not in v.items or k not in c.items or
                   digest(v.items[k]) != digest(c.items[k]))
    return min(versions, key=unlike)


class Reference:
    """The uninterrupted run: every version of every file it committed (seen at each of its
    commits, the run stopped meanwhile), its final folder and its running time."""

    def __init__(self):
        self.versions = {}  # rel -> digest -> Content
        self.frames = {}  # series file -> frame -> digest
        self.final = {}
        self.seconds = 0.0
        self.commits = 0

    def record(self, contents):
        for rel, c in contents.items():
            if c.error is None:
                self.versions.setdefault(rel, {}).setdefault(c.digest, c)
                if c.frames:
                    self.frames.setdefault(rel, {}).update(c.frames)


def inspect(folder, contents, ref):
    """What is wrong with the folder as it is (the run stopped or killed)."""
    problems = []
    for rel, c in sorted(contents.items()):
        name = os.path.basename(rel)
        if c.error:
            problems.append("%s looks finished but cannot be read (%s)" % (rel, c.error))
            continue
        for h5, dataset, dims in c.refs:
            target = os.path.join(os.path.dirname(rel), h5)
            t = contents.get(target)
            if t is None:
                problems.append("%s refers to %s, which is absent" % (rel, target))
                break
            if t.error is None and t.shapes.get(dataset) != dims:
                problems.append("mixed set: %s refers to %s:/%s %s, which %s holds as %s"
                                % (rel, target, dataset, dims, target,
                                   t.shapes.get(dataset, "nothing")))
                break
        if name.endswith("_stage"):
            k = int(Path(folder.path, rel).read_text())
            base = rel[:-len("_stage")]
            missing = [f for f in ("%s_stage%d_state.h5" % (base, k),
                                   "%s_stage%d_restart.h5" % (base, k),
                                   "%s_stage%d.h5" % (base, k),
                                   "%s_stage%d.index" % (base, k)) if f not in contents]
            if missing:
                problems.append("%s names stage %d, whose checkpoint lacks %s"
                                % (rel, k, ", ".join(missing)))
        # A finished unit's index is what a resume trusts (deal_study_units), also after
        # summary.json (a resume then starts by removing it); a stage's index only counts
        # through its pointer (checked above).
        if name.endswith(".index") and \
                not re.search(r"_stage\d+\.index$", name) and \
                rel[:-len(".index")] + ".h5" not in contents:
            problems.append("%s is there without its %s.h5" % (rel, rel[:-len(".index")]))
        if ref is None:
            continue
        if c.frames is not None and rel in ref.frames:
            strange = [g for g, d in c.frames.items() if ref.frames[rel].get(g) != d]
            if strange:
                problems.append("%s holds frames the uninterrupted run did not write: %s"
                                % (rel, ", ".join(sorted(strange)[:4])))
        elif rel in SERIES.values():
            pass  # its frame list follows its series file (checked through its refs)
        elif rel == PARTS:
            pass  # run records (wall times): parts_checks
        elif c.digest not in ref.versions.get(rel, {}):
            known = ref.versions.get(rel)
            why = "a file the uninterrupted run never wrote" if not known else \
                "a version the uninterrupted run never wrote; against its closest version: " + \
                "; ".join(differences(closest(known.values(), c), c))
            problems.append("%s: %s" % (rel, why))
    if "summary.json" in contents and ref is not None:
        problems += compare_final(contents, ref, extra_allowed=True)
    return problems


def parts_of(contents):
    c = contents.get(PARTS)
    return list(c.parts) if c is not None and c.parts is not None else []


def parts_checks(before, contents, resumed, killed, summary_path):
    """The record of a run made of parts. A resumed run starts from the parts file it finds
    (`before`); killed, it leaves those lines and at most one more, its own, "interrupted"
    (when it reached a progress report), or no file once its summary is there; ending by
    itself it folds exactly those lines into summary.json's earlier_parts and removes the
    file. A fresh run has no earlier parts."""
    problems = []
    earlier = parts_of(before) if resumed else []
    if killed:
        if not resumed:
            return problems  # a fresh run may leave an old folder's file until its first report
        now = parts_of(contents)
        if not now and PARTS not in contents:
            if earlier and "summary.json" not in contents:
                problems.append("%s is gone, with the %d earlier parts it listed, and no "
                                "summary holds them" % (PARTS, len(earlier)))
            return problems
        if now[:len(earlier)] != earlier or len(now) > len(earlier) + 1:
            problems.append("%s holds %d lines where the run found %d and may add one: %s" % (
                PARTS, len(now), len(earlier), [p.get("status") for p in now]))
        elif len(now) == len(earlier) + 1 and now[-1].get("status") != "interrupted":
            problems.append("the killed part's line in %s says %r, not \"interrupted\"" % (
                PARTS, now[-1].get("status")))
        return problems
    if PARTS in contents:
        problems.append("%s is left beside the finished run's summary.json" % PARTS)
    try:
        run = json.loads(Path(summary_path).read_text())["run"]
    except (OSError, ValueError, KeyError) as e:
        return problems + ["summary.json has no run record (%s)" % e]
    listed = run.get("earlier_parts", [])
    if listed != earlier:
        problems.append("summary.json lists %d earlier parts %s where the run found %d %s" % (
            len(listed), [p.get("status") for p in listed], len(earlier),
            [p.get("status") for p in earlier]))
    elif earlier:
        total = run["wall_time_s"] + sum(p["wall_time_s"] for p in earlier)
        if abs(run.get("wall_time_all_parts_s", -1) - total) > 1e-6 * total:
            problems.append("wall_time_all_parts_s %r is not the sum of the parts' %r" % (
                run.get("wall_time_all_parts_s"), total))
    return problems


def changes(before, after):
    """What a run did to a folder (it should have done nothing)."""
    out = ["removed %s" % rel for rel in sorted(set(before) - set(after))]
    out += ["wrote %s" % rel for rel in sorted(set(after) - set(before))]
    out += ["changed %s" % rel for rel in sorted(set(before) & set(after))
            if before[rel].digest != after[rel].digest]
    return out


def compare_final(contents, ref, extra_allowed=False):
    """The folder against the uninterrupted run's final folder."""
    problems = []
    for rel in sorted(set(ref.final) - set(contents)):
        problems.append("%s is missing (the uninterrupted run left it)" % rel)
    if not extra_allowed:
        for rel in sorted(set(contents) - set(ref.final)):
            problems.append("%s is left over (the uninterrupted run did not leave it)" % rel)
    for rel in sorted(set(ref.final) & set(contents)):
        a, b = ref.final[rel], contents[rel]
        if b.error:
            continue  # reported by inspect
        if a.frames is not None:
            last = max(a.frames)
            strange = [g for g, d in b.frames.items() if a.frames.get(g) != d]
            if strange or b.frames.get(last) != a.frames[last]:
                problems.append("%s: frames differ from the uninterrupted run's: %s"
                                % (rel, ", ".join(sorted(strange + [last])[:4])))
            continue
        if rel in SERIES.values():
            continue
        if a.digest != b.digest:
            problems.append("%s differs from the uninterrupted run's: %s"
                            % (rel, "; ".join(differences(a, b))))
    return problems


def stopped_at_events(engine, watch):
    """Yields the events of each burst of file operations, with the run stopped (SIGSTOP)
    right after them; the caller inspects the folder and continues or kills the run."""
    while not engine.finished():
        events = watch.read(0.05)
        if events:
            engine.stop()
            yield events + watch.read(0)


class Test:
    def __init__(self, args):
        self.args = args
        self.granular = str(Path(args.granular).resolve())
        self.scene = str(Path(args.scene).resolve())
        self.rng = random.Random(args.seed)
        self.work = Path(args.work).resolve() if args.work else \
            Path(tempfile.mkdtemp(prefix="granular_kill_resume_"))
        self.work.mkdir(parents=True, exist_ok=True)
        no_charts = self.work / "no_charts"
        no_charts.mkdir(exist_ok=True)
        self.env = ensemble_test.mpi_env()
        self.env["GRANULAR_PLOTS_DIR"] = str(no_charts)
        self.mpiexec = os.environ.get("MPIEXEC") or "mpiexec"
        self.no_kill_at = re.compile(args.no_kill_at) if args.no_kill_at else None
        self.problems = []
        self.seen = {}
        self.kills = []
        self.runs = 0
        self.mpi_kills = 0
        self.notes = []

    def command(self, out, resume, ranks):
        cmd = [self.granular, "run", self.scene, "--out", str(out), "--threads", "1",
               "--quiet"] + (["--resume"] if resume else [])
        if ranks:
            cmd = [self.mpiexec, "--oversubscribe", "--bind-to", "none", "-np", str(ranks)] + cmd
        return cmd

    def start(self, out, resume, ranks):
        self.runs += 1
        return Engine(self.command(out, resume, ranks), self.env,
                      str(self.work / ("run%03d.log" % self.runs)), bool(ranks))

    def fail(self, what, engine=None):
        """Records a finding; the same finding at later kills is counted, not printed."""
        shape = re.sub(r"\d+", "#", what)
        self.seen[shape] = self.seen.get(shape, 0) + 1
        self.problems.append(what)
        if self.seen[shape] > 1:
            return
        print("FAILED:", what)
        if engine is not None:
            print("    command:", " ".join(engine.cmd))
            tail = engine.log_tail().strip()
            if tail:
                print("    " + tail.replace("\n", "\n    "))

    # ---- the uninterrupted run -------------------------------------------------------
    def reference(self):
        # In one plain process, for the tests over MPI ranks as well: the ranks write the
        # same files as one process (the MpiEnsemble tests check that), and a run of one
        # process is the one that can be stopped at every commit without mpiexec's start-up.
        out = self.work / "uninterrupted"
        out.mkdir()
        folder, watch, ref = Folder(out), Watch(out), Reference()
        engine = self.start(out, False, 0)
        for events in stopped_at_events(engine, watch):
            ref.commits += sum(kind == "commit" for kind, _ in events)
            contents = folder.contents()
            ref.record(contents)
            for p in inspect(folder, contents, None):
                self.fail("uninterrupted run: " + p)
            self.check_events(events, engine)
            engine.cont()
        ref.seconds = engine.active_seconds()
        watch.close()
        if engine.p.returncode != 0:
            self.fail("the uninterrupted run failed (exit %d)" % engine.p.returncode, engine)
            return None
        ref.final = folder.contents()
        ref.record(ref.final)
        print("uninterrupted run: %.2f s, %d commits, %d files: %s"
              % (ref.seconds, ref.commits, len(ref.final), ", ".join(sorted(ref.final))))
        return ref

    # ---- one run of a chain ---------------------------------------------------------
    def kill_key(self, kind, rel, contents):
        """What a kill point is: a file version for a commit; for a removal, the kind of file
        removed in that folder (stage numbers and variants alike)."""
        if self.no_kill_at and self.no_kill_at.search(rel):
            return None
        if kind == "removal":
            return ("removal", os.path.dirname(rel), re.sub(r"\d+", "#", os.path.basename(rel)))
        c = contents.get(rel)
        return (kind, rel, c.digest if c else "gone")

    def drive_commits(self, engine, watch, folder, ref, killed):
        """Stops the run at each event; kills it at the first kill point not killed at yet.
        Returns the event it was killed after, or None when the run ended."""
        for events in stopped_at_events(engine, watch):
            contents = folder.contents()
            where = "after %s of %s" % events[-1]
            problems = inspect(folder, contents, ref)
            for p in problems:
                self.fail("%s (stopped %s)" % (p, where), engine)
            self.check_events(events, engine)
            # A folder found wrong is also killed at once, to see what a resume makes of it.
            keys = [(self.kill_key(kind, rel, contents), (kind, rel)) for kind, rel in events]
            keys += [(("problem", re.sub(r"\d+", "#", p)), events[-1]) for p in problems]
            new = [(k, e) for k, e in keys if k is not None and k not in killed]
            if new and engine.p.poll() is None:
                killed.update(k for k, _ in new)
                engine.kill("job")
                return new[0][1]  # the first event not killed at before
            engine.cont()
        return None

    def drive_random(self, engine, watch, delay, how):
        """Kills the run `delay` seconds after its start, unless it ends first. Returns the
        last event before the kill, ("start", "") if there was none, or None when the run
        ended."""
        last = ("start", "")
        deadline = engine.started + delay
        while not engine.finished():
            now = time.monotonic()
            if now >= deadline:
                before = watch.read(0)  # what happened up to the kill
                self.check_events(before, engine)
                last = before[-1] if before else last
                killed_at = time.monotonic()
                note = engine.kill(how, self.rng)
                lasted = time.monotonic() - killed_at
                events = watch.read(0)
                if note:
                    self.fail(note, engine)
                late = [e for e in events if e[0] != "overflow"]
                if late and how != "job":
                    self.notes.append("kill %d: after %s was killed, the rest of the job lived "
                                      "%.2f s more and went on to %s" % (
                                          len(self.kills) + 1, how, lasted,
                                          ", ".join("%s of %s" % e for e in late)))
                self.check_events(events, engine)
                return last
            events = watch.read(min(0.02, deadline - now))
            self.check_events(events, engine)
            if events:
                last = events[-1]
        return None

    def check_events(self, events, engine):
        for kind, rel in events:
            if kind == "in place":
                self.fail("%s is written in place under its final name" % rel, engine)

    # ---- chains of runs -------------------------------------------------------------
    def chain(self, ref, index, killed):
        """Runs one chain: a fresh run, then after every kill a resume (as after any kill,
        also when the folder already looks finished), until a run ends by itself. Returns
        whether a run failed (a new chain then goes on past that kill point)."""
        out = self.work / ("chain%02d" % index)
        out.mkdir()
        folder, watch = Folder(out), Watch(out)
        resume, ranks = False, self.args.ranks
        try:
            while True:
                before = folder.contents()
                engine = self.start(out, resume, ranks)
                if self.args.mode == "commits":
                    at, how = self.drive_commits(engine, watch, folder, ref, killed), "job"
                elif len(self.kills) < self.args.kills:
                    span = ref.seconds + (self.launch if ranks else 0)
                    how = "job"
                    if ranks:  # each way of killing a job over MPI in turn
                        how = ["job", "mpiexec", "rank"][self.mpi_kills % 3]
                        self.mpi_kills += 1
                    self.delay = self.rng.uniform(0, span)
                    at = self.drive_random(engine, watch, self.delay, how)
                else:
                    at = self.drive_random(engine, watch, 1e9, "job")
                watch.read(0)
                contents = folder.contents()
                if at is None:  # the run ended by itself
                    if engine.p.returncode != 0:
                        if resume and "--resume: no checkpoint at" in engine.log_tail():
                            # Refused: then it must have left the folder as it was.
                            for p in changes(before, contents):
                                self.fail("chain %d: a resume refused for want of a checkpoint "
                                          "%s" % (index, p), engine)
                            if "summary.json" in before:
                                return False  # finished before; compared after its kill
                            resume = False  # killed before its first checkpoint: start again
                            continue
                        said = [l for l in engine.log_tail(1 << 20).splitlines()
                                if re.match(r"(rank \d+: )?(error|stopped)", l)]
                        self.fail("chain %d: the %s failed (exit %d)%s" % (
                            index, "resumed run" if resume else "run", engine.p.returncode,
                            ": " + said[-1] if said else ""), engine)
                        return True
                    for p in inspect(folder, contents, ref) + compare_final(contents, ref) + \
                            parts_checks(before, contents, resume, False, out / "summary.json"):
                        self.fail("chain %d, finished run: %s" % (index, p), engine)
                    left = partial_files(out)
                    if left:
                        self.notes.append("chain %d ended with partial files left behind: %s"
                                          % (index, ", ".join(left)))
                    print("chain %d: a run finished after %d kills in the chain%s" % (
                        index, sum(k[0] == index for k in self.kills),
                        "" if self.problems else "; the outputs equal the uninterrupted run's"))
                    return False
                self.kills.append((index, at, how, ranks))
                if self.args.mode == "commits":
                    moment = "right after %s of %s" % at
                else:
                    moment = "at %.3f s, %s" % (self.delay, "before any file event" if at[0] ==
                                                "start" else "last file event: %s of %s" % at)
                print("kill %d (chain %d, %s%s): %s%s" % (
                    len(self.kills), index, "%d ranks, " % ranks if ranks else "",
                    "killed " + how, moment,
                    " (summary.json there)" if "summary.json" in contents else ""))
                for p in inspect(folder, contents, ref) + \
                        parts_checks(before, contents, resume, True, None):
                    self.fail("after kill %d (%s of %s): %s" % (len(self.kills), at[0], at[1],
                                                                p), engine)
                resume = True
                if self.args.mode == "random" and ranks:
                    ranks = self.rng.choice([self.args.ranks, 0])
        finally:
            watch.close()

    def run(self):
        started = time.monotonic()
        ref = self.reference()
        if ref is None:
            return 1
        self.launch = 0.0
        if self.args.ranks:
            # mpiexec's start-up, so that random kills spread over the whole run.
            t = time.monotonic()
            subprocess.run([self.mpiexec, "--oversubscribe", "--bind-to", "none", "-np",
                            str(self.args.ranks), self.granular, "check", self.scene],
                           env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            self.launch = time.monotonic() - t
        killed = set()
        index = 0
        while True:
            index += 1
            failed = self.chain(ref, index, killed)
            if not failed and (self.args.mode == "commits" or len(self.kills) >= self.args.kills):
                break
            if index >= 200:
                self.fail("no end after 200 chains")
                break
        for n in self.notes:
            print("note:", n)
        print("%s: %d kills, %d runs, %d chains, %.1f s (%s)" % (
            "FAILED" if self.problems else "passed", len(self.kills), self.runs, index,
            time.monotonic() - started, " ".join(sys.argv[2:])))
        if self.problems:
            print("reproduce: /usr/bin/python3 %s %s --keep" % (
                sys.argv[0], " ".join(sys.argv[1:])))
            if self.args.keep:
                print("work folder kept:", self.work)
        return 1 if self.problems else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("granular")
    ap.add_argument("scene")
    ap.add_argument("mode", choices=["random", "commits"])
    ap.add_argument("--ranks", type=int, default=0)
    ap.add_argument("--kills", type=int, default=8, help="random mode: how many kills")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-kill-at", default="")
    ap.add_argument("--work", default="")
    ap.add_argument("--keep", action="store_true", help="keep the work folder")
    args = ap.parse_args()
    test = Test(args)
    try:
        return test.run()
    finally:
        if not args.keep:
            shutil.rmtree(test.work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
