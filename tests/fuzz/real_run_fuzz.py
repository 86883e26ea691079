#!/usr/bin/python3
"""Runs mutated scene files to their end and checks how each run ends.

    real_run_fuzz.py GRANULAR [--mutants N] [--seed S] [--scenes a,b] [--timeout T]
                     [--keep DIR] [--list] [--verbose] [--strict-nan]

tests/core/io/test_scene_file_fuzz.cpp mutates every shipped scene file and only *checks* it; this
script *runs* the mutants, so that what the checks let through meets the drivers, the
kernels and the output writers. Each shipped scene file is first shrunk to a run of a second
or two (SHRINK below); a mutant is a shrunk scene with one or two mutations: a hostile
value, a number scaled, a line dropped, a list entry repeated, a list reordered. Mutant
`index` of seed `S` is drawn from random.Random(f"{S}:{index}") alone, so one failure is
reproduced by its pair (`--seed S --mutants index+1`, or the file saved by --keep).

Every run must end in one of these ways:
  ok       exit 0, every number of summary.json finite or null, no inf in results.h5, and NaN
           only in the datasets where the shrunk scene's own run has NaN: the engine writes
           NaN for "not applicable" (a closed form that does not exist, a check not run);
  ok-nan   the same, but NaN in a dataset that is finite in the shrunk scene's run: the
           mutant made something not applicable (an unjammed packing, a picker that finds
           nothing) or broke it; these are listed for review, and fail with --strict-nan;
  refused  exit 2 (InputError) with a message that names the scene file;
  stopped  exit 3 (PhysicsError) with a message saying what happened.
Anything else fails: a signal, a timeout, exit 1 (an exception that is neither of the two
error types), text from a library instead of the engine's own message, a refusal that does
not name the file, non-finite output of a finished run, or partial files left in the output
folder (core/io/output.cpp writes "<dir>/.<name>.partial" and renames it when complete).

GRANULAR_PLOTS_DIR points at an empty folder, so the engine skips charts and the report with
a note (core/io/output.cpp, run_python_script) instead of starting matplotlib for every mutant.
results.h5 is read with h5dump when it exists, else through the HDF5 library the engine links
(ctypes), else not at all; the totals line says which.

--list runs the shrunk scenes themselves and prints their outcome and time. The exit status is
1 when any run fails (or, with --list, a shrunk scene does not end as SHRINK expects).

Mutated scenes are written to a temporary folder, never into scenarios/ (the C++ tests list
every *.toml there); input paths of the shrunk scenes are made absolute so they still resolve.
"""
import argparse
import ctypes
import ctypes.util
import fnmatch
import json
import math
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from array import array
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"

# ---- shrinking ---------------------------------------------------------------------------
# Per driver: `base` is how the shrunk scene is expected to end ("ok", or "stopped" where the
# driver cannot finish in seconds and a clean physics stop is accepted instead), `set` maps
# "table.key" to new TOML text or to ("first", n), which keeps the first n entries of a list,
# and `files` holds the same per scene-file stem, on top of `set` (None there: leave the key
# alone). Keys change only where a file has them (a key may be a pattern with "*"); a key
# marked "+" is added where it is missing, under its table's header or in a new table.
# The aim is a run of at most 1-3 s with --threads 1 that still passes through every stage of
# the driver (preparation, probing, analysis, output), so that a mutant reaches them all.
SHRINK = {
    # Two spheres per pair, a few hundred steps each: already a fraction of a second.
    "two_particle_linear": {"base": "ok", "set": {}},
    "hysteretic_collision": {"base": "ok", "set": {}},
    "soft_collision": {"base": "ok", "set": {}},
    "lammps_forces": {"base": "ok", "set": {}},
    # One sphere against a wall or a sphere per speed and angle: well under a second.
    "impact": {"base": "ok", "set": {}},
    # 16 cases of up to 17 sweep values: three values per case keep every test type.
    "impact_benchmarks": {"base": "ok", "set": {"cases.*.values": ("first", 3)}},
    # The synthetic study's cost is seeds x noise levels; its samples must cover both pulses.
    "signal_analysis": {"base": "ok", "set": {"synthetic.seeds": "3"}},
    # Cost is beads x realizations x steps; the front must stay inside the chain, so t_max
    # shrinks with the beads (front speed about 1.2 beads per unit time).
    "chain_impulse": {"base": "ok", "set": {
        "chain.beads": "128", "disorder.realizations": "6", "disorder.xi": ("first", 2),
        "time.t_max": "64"},
        "files": {
            "chain_impulse_centre": {"chain.beads": "257"},
            # The exact solver diagonalises each chain: fewer beads; its analysis windows
            # must fit inside them.
            "chain_impulse_exact": {"chain.beads": "96", "time.t_max": "48",
                                    "analysis.near_source_beads": "10",
                                    "analysis.power_law_beads": "60"},
        }},
    # The full scene is the quick one at a larger size: use the quick sizes, and windows and
    # validation bands that fit them.
    "chain_master_equation": {"base": "ok", "set": {
        "chain.beads": "63", "disorder.xi": ("first", 2), "disorder.realizations": "8",
        "bands.count": "8", "time.samples": "30", "validation.bands": "[1, 5]"},
        "files": {"chain_master_equation": {
            "fit.window_global": "[0, 30]", "validation.samples": "40",
            "cost.realizations": "100", "cost.horizon": "100"}}},
    "chain_tones": {"base": "ok", "set": {
        "chain.beads": "63", "disorder.xi": ("first", 2), "disorder.realizations": "8",
        "bands.count": "8", "time.samples": "40"},
        "files": {"chain_tones": {"wave.tones": "[1, 4, 24]", "wave.bands": "[5]",
                                  "fit.tone": "4"}}},
    # The material-point fits are cheap at a coarser stretch step; the DEM pure shear is the
    # cost: fewer particles, faster compression and shear, fewer samples.
    "continuum_fit": {"base": "ok", "set": {
        "law.step": "1.0e-3", "shear.count": "64", "shear.volumetric_strain_rate": "2.0e-2",
        "shear.relax_max_steps": "3000", "shear.strain": "0.01", "shear.strain_rate": "1.0e-3",
        "shear.samples": "10"}},
    # A small periodic packing: 128 spheres compressed ten times faster, short relaxation.
    "isotropic_compression": {"base": "ok", "set": {
        "particles.count": "128", "compression.volumetric_strain_rate": "1.0e-2",
        "compression.relax_steps": "2000", "run.checkpoint_every": "5000",
        "output.snapshot_every": "5000"}},
    # Soft spheres settled under gravity, then compressed between walls: 20 spheres in a
    # small box, a lower drop, settled to a looser kinetic-energy ratio (the 3 ms settling
    # limit is kept: shorter ones stop the run), a coarser time step, less strain.
    "confined_compression": {"base": "ok", "set": {
        "box.size": "[50.0, 50.0, 60.0]", "fill.count": "20", "fill.region_height": "150.0",
        "fill.kinetic_energy_ratio": "1e-4", "compression.time_step": "20.0",
        "compression.strain": "0.1", "output.snapshot_every": "100"}},
    # One target and one variant per study, 64 spheres compressed ten times faster (the
    # quick files' inertial-number control too) and probed with short relaxations; the gas
    # stage's rate and the probe's step limit are added where a file leaves them default.
    "elastic_moduli": {"base": "ok", "set": {
        "particles.count": "64", "preparation.targets": ("first", 1),
        "preparation.mu": ("first", 1), "preparation.kc": ("first", 1),
        "preparation.dt": ("first", 1), "preparation.volumetric_strain_rate": "1.0e-2",
        "preparation.inertial_number": "1.0e-2",
        "preparation.min_volumetric_strain_rate": "1.0e-3",
        "+preparation.gas_strain_rate": "2.0e-2", "preparation.relax_max_steps": "4000",
        "probe.strain_steps": "200", "probe.relax_steps": "200",
        "+probe.max_strain_steps": "2000", "probe.amplitudes": ("first", 2),
        "probe.prestrains": ("first", 1), "probe.kt_over_kn": ("first", 2),
        "probe.halving_check": "false", "ensemble.counts": "[64]",
        "ensemble.seeds": ("first", 1), "probe.orientations": "1"}},
    # Each mixture is a servo-controlled packing probed at each pressure; the pair-rule check
    # needs its soft fraction (0.2) among the mixtures.
    "mixture_moduli": {"base": "ok", "set": {
        "particles.count": "64", "mixture.soft_volume_fractions": "[0.0, 0.2]",
        "preparation.pressures": ("first", 1), "preparation.max_checks": "20",
        "pair_rule_check.pressures": ("first", 1)}},
    # A column between walls, servo-pushed to each pressure, then pulsed and probed. The servo
    # is the cost: a shorter column, the time step near its t_c/10 limit, a faster wall, a
    # looser tolerance and shorter holds (a short max_time stops the run instead).
    "wave_transmission": {"base": "ok", "set": {
        "column.length": "8.0", "preparation.pressures": ("first", 1), "run.dt": "0.15",
        "preparation.wall_speed": "0.004", "preparation.tolerance": "0.2",
        "preparation.relax_time": "20.0", "preparation.max_time": "300000.0",
        "preparation.final_relax_time": "100.0",
        "pulse.amplitude_factors": ("first", 1), "pulse.record_time": "150.0",
        "probe.ramp_time": "50.0", "probe.hold_time": "50.0", "run.dt_check": ("first", 1),
        "run.restitution_check": ("first", 1), "output.snapshot_every": "1000"},
        "files": {"wave_transmission": {"column.width": "4.0"},
                  # Rubber's stiffer, lighter pairs: t_c/10 is 0.118 there.
                  "wave_transmission_mixture_quick": {"run.dt": "0.11"}}},
}

# Values that broke parsers and drivers elsewhere (the list of test_scene_file_fuzz.cpp,
# less those that only test the parser).
HOSTILE = ["nan", "inf", "-inf", "-1", "0", "-0.0", "1e308", "1e-320", "9223372036854775807",
           "2147483648", '""', '"x"', "true", "[]", "[nan]", "[1e308, -1]", "{}"]
SCALES = [-1.0, 0.5, 2.0, 10.0, 0.1, 1e-6]

# Keys whose size is the run's cost (larger = longer) and keys whose size divides it (smaller
# = longer): scaling must not make a legitimate run outlast the timeout, so these only move
# the cheap way or by a factor 2. Hostile values still hit them: those the engine must refuse.
COST_UP = re.compile(r"(count|counts|beads|realizations|samples|steps|t_max|duration|_time|"
                     r"horizon|seeds|substeps|max_checks|length|width|size|region_height|"
                     r"strain|amplitude_factors|pressures|targets|values|speeds|angles_deg|"
                     r"xi|mu|kc|tones|bands|noise|band_fractions|strain_gamma|stress_beta|"
                     r"steps_per_contact|realization|phi_max|nu_end|volume_fractions)$")
COST_DOWN = re.compile(r"(dt|time_step|timestep|rate|step|speed|wall_speed|sample_every|"
                       r"every|velocity|tolerance|ratio|max_push|kinetic_energy_ratio|"
                       r"relax_ratio|ekin_ratio|max_step|check_crossings|skin|diameter|"
                       r"diameter_mean|diameter_min|diameter_max)$")

PASS_KINDS = ("ok", "ok-nan", "refused", "stopped")
FAIL_KINDS = ("signal", "timeout", "exit1", "exit-other", "library-text", "unnamed-refusal",
              "silent-stop", "nonfinite-output", "bad-output", "partial-left")

# Text that comes from a library or the runtime, not from the engine's own messages.
LIBRARY_TEXT = ["terminate called", "bad_alloc", "HDF5-DIAG", "what():", "Kokkos::",
                "Assertion", "Segmentation fault", "core dumped", "std::", "basic_string",
                "vector::", "stoi", "stod", "stol", "out_of_range", "length_error",
                "double free", "free():", "malloc", "AddressSanitizer", "runtime error:"]


# ---- TOML as text ------------------------------------------------------------------------
class Entry:
    """One `key = value` of a scene text: its full dotted key and where its text lies."""

    def __init__(self, key, table, line_start, value_start, value_end, line_end):
        self.key, self.table = key, table
        self.line_start, self.value_start = line_start, value_start
        self.value_end, self.line_end = value_end, line_end


HEADER = re.compile(r"[ \t]*\[\[?[ \t]*([^\]\n]+?)[ \t]*\]\]?[ \t]*(#[^\n]*)?$")
ASSIGN = re.compile(r"[ \t]*([A-Za-z0-9_\-.\" ]+?)[ \t]*=")


def value_end(text, i):
    """End of the value that starts at text[i] (past '='): strings, nested arrays and inline
    tables across lines are followed; a comment or the end of the line at depth 0 ends it."""
    depth, n = 0, len(text)
    while i < n:
        c = text[i]
        if c in "\"'":
            q = c * 3 if text.startswith(c * 3, i) else c
            j = i + len(q)
            while j < n and not text.startswith(q, j):
                j += 2 if (c == '"' and text[j] == "\\") else 1
            i = j + len(q)
            continue
        if c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "#":
            if depth == 0:
                break
            while i < n and text[i] != "\n":
                i += 1
            continue
        elif c == "\n" and depth <= 0:
            break
        i += 1
    return i


def entries(text):
    """Every assignment of `text`, in order, with the table it belongs to."""
    found, table, pos = [], "", 0
    while pos < len(text):
        eol = text.find("\n", pos)
        eol = len(text) if eol < 0 else eol
        line = text[pos:eol]
        h = HEADER.match(line)
        a = ASSIGN.match(line)
        if h and not a:
            table = ".".join(p.strip().strip('"') for p in h.group(1).split("."))
            pos = eol + 1
            continue
        if a and not line.lstrip().startswith("#"):
            key = ".".join(p.strip().strip('"') for p in a.group(1).split("."))
            vstart = pos + a.end()
            vend = value_end(text, vstart)
            vtext = text[vstart:vend]
            vstart += len(vtext) - len(vtext.lstrip())
            vend = vstart + len(text[vstart:vend].rstrip())
            lend = text.find("\n", vend)
            lend = len(text) if lend < 0 else lend + 1
            full = f"{table}.{key}" if table else key
            found.append(Entry(full, table, pos, vstart, vend, lend))
            pos = lend
            continue
        pos = eol + 1
    return found


def parse_value(text):
    return tomllib.loads("v = " + text)["v"]


def toml_value(v):
    """TOML text of a Python value read by tomllib (or made from one)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        items = [f"{k if re.fullmatch(r'[A-Za-z0-9_-]+', k) else json.dumps(k)} = "
                 f"{toml_value(x)}" for k, x in v.items()]
        return "{ " + ", ".join(items) + " }" if items else "{}"
    raise TypeError(f"no TOML text for {v!r}")


def set_key(text, key, new):
    """`text` with `key` (dotted, "table.key", may hold "*") set to `new`: TOML text, or
    ("first", n). A missing key is added, under its table's header or in a new table at the
    end, only if it is marked "+" ("+table.key")."""
    add = key.startswith("+")
    key = key.lstrip("+")
    hits = [e for e in entries(text) if fnmatch.fnmatchcase(e.key, key)]
    if not hits and (not add or isinstance(new, tuple)):
        return text
    for e in reversed(hits):  # from the end, so earlier offsets stay valid
        if isinstance(new, tuple):
            old = parse_value(text[e.value_start:e.value_end])
            if not isinstance(old, list) or len(old) <= new[1]:
                continue
            new_text = toml_value(old[:new[1]])
        else:
            new_text = new
        text = text[:e.value_start] + new_text + text[e.value_end:]
    if hits:
        return text
    table, _, name = key.rpartition(".")
    in_table = [e for e in entries(text) if e.table == table]
    line = f"{name} = {new}\n"
    if in_table:
        at = in_table[-1].line_end
        return text[:at] + ("" if text[:at].endswith("\n") else "\n") + line + text[at:]
    for m in re.finditer(r"(?m)^[ \t]*\[[ \t]*([^\]\n]+?)[ \t]*\][ \t]*(#[^\n]*)?$", text):
        if m.group(1).replace(" ", "") == table:
            at = m.end() + 1
            return text[:at] + line + text[at:]
    if not table:
        return line + text
    return text.rstrip("\n") + f"\n\n[{table}]\n" + line


def absolute_inputs(text, folder):
    """Relative paths (strings naming a file or folder beside the scene) made absolute, so the
    scene resolves them from a temporary folder too."""
    for e in reversed(entries(text)):
        try:
            v = parse_value(text[e.value_start:e.value_end])
        except tomllib.TOMLDecodeError:
            continue
        if isinstance(v, str) and v and not os.path.isabs(v) and (folder / v).exists():
            path = str((folder / v).resolve())
            text = text[:e.value_start] + json.dumps(path) + text[e.value_end:]
    return text


class Base:
    """A shipped scene file and its shrunk text."""

    def __init__(self, path):
        self.path, self.stem = path, path.stem
        original = path.read_text()
        self.driver = tomllib.loads(original)["scene"]
        spec = SHRINK.get(self.driver, {"base": "ok", "set": {}})
        self.expected = spec["base"]
        changes = dict(spec["set"])
        changes.update(spec.get("files", {}).get(self.stem, {}))
        text = original
        for key, new in changes.items():
            if new is not None:
                text = set_key(text, key, new)
        self.text = absolute_inputs(text, path.parent)
        tomllib.loads(self.text)  # the shrunk scene must still be TOML


def shipped_bases(only):
    files = sorted(SCENARIOS.glob("*/*.toml"))
    if only:
        wanted = set(only)
        files = [f for f in files if f.stem in wanted]
        missing = wanted - {f.stem for f in files}
        if missing:
            raise SystemExit(f"no scene file scenarios/*/<name>.toml for {sorted(missing)}")
    return [Base(f) for f in files]


# ---- mutation ----------------------------------------------------------------------------
def leaf_paths(v, at=()):
    """Paths to the scalar leaves inside lists and inline tables of a value."""
    if isinstance(v, list):
        return [p for i, x in enumerate(v) for p in leaf_paths(x, at + (i,))]
    if isinstance(v, dict):
        return [p for k, x in v.items() for p in leaf_paths(x, at + (k,))]
    return [at]


def get_at(v, path):
    for p in path:
        v = v[p]
    return v


def put_at(v, path, new):
    if not path:
        return new
    get_at(v, path[:-1])[path[-1]] = new
    return v


def scaled(x, factor, key):
    """x times factor, unless that makes the run much longer (COST_UP, COST_DOWN): None."""
    name = key.rsplit(".", 1)[-1]
    if COST_UP.search(name) and abs(factor) > 2:
        return None
    if COST_DOWN.search(name) and abs(factor) < 0.5:
        return None
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    y = x * factor
    return int(round(y)) if isinstance(x, int) else y


def mutate_once(text, rng):
    """One mutation of `text`: (new text, what was done)."""
    es = [e for e in entries(text) if e.key != "scene"]
    kind = rng.choices(["hostile", "scale", "drop", "duplicate", "reorder"],
                       weights=[40, 30, 10, 10, 10])[0]
    values = {}
    for e in es:
        try:
            values[e.key] = parse_value(text[e.value_start:e.value_end])
        except tomllib.TOMLDecodeError:
            values[e.key] = None
    lists = [e for e in es if isinstance(values[e.key], list) and values[e.key]]
    numbers = [e for e in es if any(
        isinstance(get_at(values[e.key], p), (int, float)) and
        not isinstance(get_at(values[e.key], p), bool) for p in leaf_paths(values[e.key]))]
    if kind == "scale" and numbers:
        e = rng.choice(numbers)
        v = values[e.key]
        paths = [p for p in leaf_paths(v) if isinstance(get_at(v, p), (int, float))
                 and not isinstance(get_at(v, p), bool)]
        p = rng.choice(paths)
        factors = [f for f in SCALES if scaled(get_at(v, p), f, e.key) is not None]
        if factors:
            f = rng.choice(factors)
            new = toml_value(put_at(v, p, scaled(get_at(v, p), f, e.key)))
            where = e.key + "".join(f"[{x}]" if isinstance(x, int) else f".{x}" for x in p)
            return text[:e.value_start] + new + text[e.value_end:], f"{where} x{f:g}"
    if kind == "drop" and es:
        e = rng.choice(es)
        return text[:e.line_start] + text[e.line_end:], f"{e.key} dropped"
    if kind in ("duplicate", "reorder") and lists:
        e = rng.choice(lists)
        v = list(values[e.key])
        if kind == "duplicate":
            i = rng.randrange(len(v))
            v.insert(i, v[i])
            what = f"{e.key}[{i}] repeated"
        elif len(v) > 1:
            rng.shuffle(v)
            if v == values[e.key]:
                v.reverse()
            what = f"{e.key} reordered"
        else:
            v = v + v
            what = f"{e.key}[0] repeated"
        return text[:e.value_start] + toml_value(v) + text[e.value_end:], what
    # A hostile value: the whole value, or one entry of a list or inline table.
    e = rng.choice(es)
    h = rng.choice(HOSTILE)
    v = values[e.key]
    if isinstance(v, (list, dict)) and v and rng.random() < 0.5:
        p = rng.choice(leaf_paths(v))
        new = toml_value(put_at(v, p, parse_value(h)))
        where = e.key + "".join(f"[{x}]" if isinstance(x, int) else f".{x}" for x in p)
        return text[:e.value_start] + new + text[e.value_end:], f"{where} -> {h}"
    return text[:e.value_start] + h + text[e.value_end:], f"{e.key} -> {h}"


def make_mutant(bases, seed, index):
    """Mutant `index` of `seed`: (base, text, [what was done]), from its own random stream."""
    rng = random.Random(f"{seed}:{index}")
    # A driver first, then one of its files: the elastic_moduli family has 21 files and would
    # otherwise take most of the mutants.
    drivers = sorted({b.driver for b in bases})
    driver = rng.choice(drivers)
    base = rng.choice([b for b in bases if b.driver == driver])
    text, done = base.text, []
    for _ in range(rng.choice([1, 1, 2])):
        text, what = mutate_once(text, rng)
        done.append(what)
    return base, text, done


# ---- reading the outputs -----------------------------------------------------------------
class Hdf5Reader:
    """Finds non-finite values in the floating datasets of an HDF5 file."""

    def __init__(self):
        self.how, self.lib = "none", None
        if shutil.which("h5dump"):
            self.how = "h5dump"
            return
        names = ["hdf5_serial", "hdf5"]
        for name in names:
            found = ctypes.util.find_library(name)
            if not found:
                continue
            try:
                lib = ctypes.CDLL(found)
                self._bind(lib)
            except (OSError, AttributeError, ValueError):
                continue
            self.lib, self.how = lib, f"ctypes ({found})"
            return

    def _bind(self, lib):
        hid, herr = ctypes.c_int64, ctypes.c_int
        lib.H5open()
        lib.H5Eset_auto2(hid(0), None, None)  # no HDF5-DIAG output from this process
        self.double = hid.in_dll(lib, "H5T_NATIVE_DOUBLE_g").value
        self.cb_type = ctypes.CFUNCTYPE(herr, hid, ctypes.c_char_p, ctypes.c_void_p,
                                        ctypes.c_void_p)
        self.visit = getattr(lib, "H5Lvisit2", None) or lib.H5Lvisit
        self.visit.argtypes = [hid, ctypes.c_int, ctypes.c_int, self.cb_type, ctypes.c_void_p]
        for f, args, res in [
                ("H5Fopen", [ctypes.c_char_p, ctypes.c_uint, hid], hid),
                ("H5Fclose", [hid], herr), ("H5Oopen", [hid, ctypes.c_char_p, hid], hid),
                ("H5Oclose", [hid], herr), ("H5Iget_type", [hid], ctypes.c_int),
                ("H5Dget_type", [hid], hid), ("H5Tget_class", [hid], ctypes.c_int),
                ("H5Tclose", [hid], herr), ("H5Dget_space", [hid], hid),
                ("H5Sget_simple_extent_npoints", [hid], ctypes.c_int64),
                ("H5Sclose", [hid], herr),
                ("H5Dread", [hid, hid, hid, hid, hid, ctypes.c_void_p], herr)]:
            fn = getattr(lib, f)
            fn.argtypes, fn.restype = args, res

    def nonfinite(self, path):
        """{dataset: "nan" or "inf"} for the floating datasets of `path` that hold NaN or inf
        (inf wins where both occur), or None if the file could not be read."""
        if self.how == "h5dump":
            return self._nonfinite_h5dump(path)
        if self.lib is None:
            return None
        lib, names = self.lib, []
        f = lib.H5Fopen(str(path).encode(), 0, 0)
        if f < 0:
            return None
        try:
            def collect(_group, name, _info, _data):
                names.append(name.decode())
                return 0
            callback = self.cb_type(collect)
            if self.visit(f, 0, 2, callback, None) < 0:
                return None
            bad = {}
            for name in names:
                o = lib.H5Oopen(f, name.encode(), 0)
                if o < 0:
                    continue
                try:
                    if lib.H5Iget_type(o) != 5:  # H5I_DATASET
                        continue
                    t = lib.H5Dget_type(o)
                    cls = lib.H5Tget_class(t)
                    lib.H5Tclose(t)
                    if cls != 1:  # H5T_FLOAT
                        continue
                    s = lib.H5Dget_space(o)
                    n = lib.H5Sget_simple_extent_npoints(s)
                    lib.H5Sclose(s)
                    buf = array("d", bytes(8 * max(n, 0)))
                    if n > 0 and lib.H5Dread(o, self.double, 0, 0, 0,
                                             buf.buffer_info()[0]) < 0:
                        return None
                    if any(math.isinf(x) for x in buf):
                        bad[name] = "inf"
                    elif any(math.isnan(x) for x in buf):
                        bad[name] = "nan"
                finally:
                    lib.H5Oclose(o)
            return bad
        finally:
            lib.H5Fclose(f)

    @staticmethod
    def _nonfinite_h5dump(path):
        r = subprocess.run(["h5dump", "-e", str(path)], capture_output=True, text=True)
        if r.returncode != 0:
            return None
        bad, name, floating = {}, None, False
        for line in r.stdout.splitlines():
            s = line.strip()
            if s.startswith("DATASET "):
                name, floating = s.split('"')[1], False
            elif s.startswith("DATATYPE") and "H5T_IEEE_F" in s:
                floating = True
            elif floating and name:
                for token in re.findall(r"(?<![A-Za-z])-?(nan|inf)(?![A-Za-z])", s, re.I):
                    if bad.get(name) != "inf":
                        bad[name] = token.lower()
        return bad


def nonfinite_json(path):
    """Keys of summary.json that hold NaN or inf ([] when none); None if it is not JSON."""
    bad = []

    def constant(token):
        bad.append(token)
        return None

    try:
        json.loads(Path(path).read_text(), parse_constant=constant)
    except (ValueError, UnicodeDecodeError):
        return None
    return bad


# ---- running -----------------------------------------------------------------------------
class Runner:
    """Runs scene texts in one temporary folder, one process at a time."""

    def __init__(self, granular, timeout, strict_nan=False):
        self.granular, self.timeout = str(Path(granular).resolve()), timeout
        self.strict_nan = strict_nan
        self.work = Path(tempfile.mkdtemp(prefix="granular_real_run_fuzz_"))
        self.plots = self.work / "plots"  # empty: charts and report are skipped with a note
        self.plots.mkdir()
        self.h5 = Hdf5Reader()
        self.child = None
        self.markers = {}  # scene-file stem: datasets holding NaN in its shrunk run

    def nan_markers(self, base):
        """Datasets whose NaN marks "not applicable" (a closed form that does not exist, a
        check not run, a fit of too few points): those that hold NaN in the shrunk scene's own
        run. Learnt on first need, one run per scene file."""
        if base.stem not in self.markers:
            self.markers[base.stem] = set()
            result = self.run(base, base.text)
            self.markers[base.stem] = result[5]
        return self.markers[base.stem]

    def close(self):
        if self.child and self.child.poll() is None:
            os.killpg(self.child.pid, signal.SIGKILL)
            self.child.wait()
        shutil.rmtree(self.work, ignore_errors=True)

    def run(self, base, text):
        """(kind, exit code, stderr text, seconds, detail, NaN datasets) of one run of `text`, a
        mutant of `base` (or `base.text` itself)."""
        scene = self.work / f"{base.stem}.toml"
        scene.write_text(text)
        out = self.work / "out"
        shutil.rmtree(out, ignore_errors=True)
        env = dict(os.environ, GRANULAR_PLOTS_DIR=str(self.plots), OMP_NUM_THREADS="1")
        cmd = [self.granular, "run", str(scene), "--out", str(out), "--threads", "1", "--quiet"]
        start = time.monotonic()
        self.child = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      cwd=self.work, env=env, start_new_session=True)
        try:
            stdout, stderr = self.child.communicate(timeout=self.timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.child.pid, signal.SIGKILL)  # the engine and any script it started
            stdout, stderr = self.child.communicate()
            seconds = time.monotonic() - start
            return "timeout", None, stderr.decode(errors="replace"), seconds, "", set()
        seconds = time.monotonic() - start
        rc = self.child.returncode
        err = stderr.decode(errors="replace")
        nans = set()
        kind, detail = self.classify(rc, err, stdout.decode(errors="replace"), scene, out,
                                     base, text, nans)
        return kind, rc, err, seconds, detail, nans

    def classify(self, rc, err, out_text, scene, out, base, text, nans):
        if rc < 0 or rc >= 128:
            return "signal", f"signal {-rc if rc < 0 else rc - 128}"
        both = err + out_text
        lib = [t for t in LIBRARY_TEXT if t in both]
        named = scene.name in err
        if not named and re.search(r"toml::|parse error", both):
            lib.append("parser text without the file")
        if lib:
            return "library-text", ", ".join(lib)
        partial = [str(p.relative_to(out)) for p in out.rglob("*")
                   if ".partial" in p.name or p.name.endswith((".tmp", "~"))] \
            if out.exists() else []
        if partial:
            return "partial-left", ", ".join(partial)
        if rc == 0:
            summary = out / "summary.json"
            if not summary.exists():
                return "bad-output", "no summary.json"
            bad = nonfinite_json(summary)
            if bad is None:
                return "bad-output", "summary.json is not JSON"
            if bad:
                return "nonfinite-output", "summary.json holds " + ", ".join(sorted(set(bad)))
            h5 = out / "results.h5"
            bad = self.h5.nonfinite(h5) if h5.exists() else {}
            if bad is None and self.h5.how != "none":
                return "bad-output", "results.h5 cannot be read"
            bad = bad or {}
            nans.update(k for k, v in bad.items() if v == "nan")
            inf = sorted(k for k, v in bad.items() if v == "inf")
            if inf:
                return "nonfinite-output", "results.h5 inf in " + ", ".join(inf[:4])
            if text != base.text:
                new = sorted(nans - self.nan_markers(base))
                if new:
                    return ("nonfinite-output" if self.strict_nan else "ok-nan",
                            "results.h5 NaN in " + ", ".join(new[:4]))
            return "ok", ""
        if rc == 2:
            return ("refused", "") if named else ("unnamed-refusal", "")
        if rc == 3:
            m = re.search(r"stopped: (.+)", err)
            return ("stopped", "") if m and len(m.group(1).strip()) > 10 else \
                ("silent-stop", "")
        return ("exit1" if rc == 1 else "exit-other"), f"exit {rc}"


def last_lines(text, n=4):
    lines = [s for s in text.strip().splitlines() if s.strip()]
    return lines[-n:]


def list_bases(runner, bases):
    print(f"{'scene file':40} {'driver':24} {'outcome':14} {'expected':9} seconds")
    bad = 0
    for b in bases:
        kind, rc, err, seconds, detail, nans = runner.run(b, b.text)
        runner.markers[b.stem] = nans
        fine = kind == b.expected
        bad += not fine
        marks = f"  ({len(nans)} NaN-marker datasets)" if nans else ""
        print(f"{b.stem:40} {b.driver:24} {kind:14} {b.expected:9} {seconds:7.2f}"
              + (marks if fine else "   <-- " + (detail or " | ".join(last_lines(err, 2)))),
              flush=True)
    print(f"HDF5 check: {runner.h5.how}")
    return bad


def run_one(runner, bases, args, index, counts, failures, notes):
    base, text, done = make_mutant(bases, args.seed, index)
    kind, rc, err, seconds, detail, _ = runner.run(base, text)
    row = counts.setdefault(base.driver, {})
    row[kind] = row.get(kind, 0) + 1
    if kind == "ok-nan":
        notes.append(f"mutant {index} {base.stem} ({'; '.join(done)}): {detail}")
    if kind in FAIL_KINDS:
        failures.append((index, base, done, kind, rc, err, detail))
        if args.keep:
            keep = Path(args.keep)
            keep.mkdir(parents=True, exist_ok=True)
            head = (f"# real_run_fuzz.py --seed {args.seed}: mutant {index} of "
                    f"{base.path.relative_to(ROOT)}\n# {'; '.join(done)}\n"
                    f"# outcome: {kind} (exit {rc}) {detail}\n")
            (keep / f"s{args.seed}_m{index}_{base.stem}.toml").write_text(head + text)
    if args.verbose:
        print(f"{index:6} {base.stem:36} {kind:16} {seconds:6.2f}s  {'; '.join(done)}",
              flush=True)


def fuzz(runner, bases, args):
    counts, failures, notes = {}, [], []
    start = time.monotonic()
    done_count = 0
    try:
        for index in range(args.mutants):
            run_one(runner, bases, args, index, counts, failures, notes)
            done_count += 1
    except KeyboardInterrupt:
        print(f"interrupted after {done_count} mutants: totals so far", file=sys.stderr)
    wall = time.monotonic() - start

    kinds = [k for k in PASS_KINDS + FAIL_KINDS if any(k in r for r in counts.values())]
    width = {k: max(len(k), 5) + 2 for k in kinds}
    print(f"\n{'driver':24}" + "".join(f"{k:>{width[k]}}" for k in kinds) + f"{'total':>8}")
    for driver in sorted(counts):
        r = counts[driver]
        print(f"{driver:24}" + "".join(f"{r.get(k, 0):{width[k]}}" for k in kinds)
              + f"{sum(r.values()):8}")
    total = {k: sum(r.get(k, 0) for r in counts.values()) for k in kinds}
    print(f"{'all':24}" + "".join(f"{total[k]:{width[k]}}" for k in kinds)
          + f"{done_count:8}")
    print(f"{done_count} mutants (seed {args.seed}) in {wall:.0f} s; HDF5 check: "
          f"{runner.h5.how}; {len(failures)} failed")
    if notes:
        print("\nNew NaN in results.h5 (passed; review that each means \"not applicable\"):")
        for line in notes:
            print(f"  {line}")
    for index, base, done, kind, rc, err, detail in failures:
        print(f"\nFAIL {kind}: seed {args.seed} mutant {index}, {base.path.relative_to(ROOT)}"
              f" ({base.driver}), exit {rc}")
        print(f"  mutation: {'; '.join(done)}")
        if detail:
            print(f"  {detail}")
        for line in last_lines(err):
            print(f"  | {line[:300]}")
    return len(failures) + (done_count < args.mutants)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("granular", help="the engine binary (build/bin/granular)")
    p.add_argument("--mutants", type=int, default=200, help="number of mutants in all")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--scenes", default="", help="scene-file stems, comma-separated")
    p.add_argument("--timeout", type=float, default=60.0, help="seconds per run")
    p.add_argument("--keep", default="", help="save each failing mutant's scene file here")
    p.add_argument("--list", action="store_true", help="run the shrunk scenes only")
    p.add_argument("--verbose", action="store_true", help="one line per mutant")
    p.add_argument("--strict-nan", action="store_true",
                   help="fail on NaN in a dataset the shrunk scene's run has finite")
    args = p.parse_args()

    bases = shipped_bases([s for s in args.scenes.split(",") if s])
    runner = Runner(args.granular, args.timeout, args.strict_nan)

    def stop(signum, _frame):
        raise KeyboardInterrupt(f"signal {signum}")

    signal.signal(signal.SIGTERM, stop)  # ctest's timeout: clean up as on Ctrl-C
    try:
        failed = list_bases(runner, bases) if args.list else fuzz(runner, bases, args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        failed = 1
    finally:
        runner.close()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
