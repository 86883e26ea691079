#!/usr/bin/python3
"""Force-level agreement with LAMMPS: the `lammps_forces` scene against LAMMPS' own output on
the same data file, for one pair-style model over the committed configurations (orthogonal,
triclinic, dense with large overlaps).

Compared at step 0 (setup: forces of the initial state, no history) and after `steps`
velocity-Verlet steps: per-atom forces and torques, velocities, spins and displacements, the
pair pressure tensor and the kinetic energy. Each is judged normwise: max |engine - LAMMPS|
over the atoms and components divided by the largest |LAMMPS| value, <= 1e-10.

LAMMPS' output is taken live when an `lmp` binary is given (and then also checked against the
committed reference, which was made the same way: a difference there means another LAMMPS
version, reported and not failed); without one, the committed reference is used.

Usage: forces_test.py --granular BIN --model NAME --work DIR [--lmp LMP] [--write-refs]
"""
import argparse
import gzip
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOLERANCE = 1e-10

# Models: LAMMPS pair_style / pair_coeff lines, unit style, time step and steps. SI: spheres
# of 0.8-1.2 mm, 1200-2500 kg/m^3, 0.3 m/s, 600 rad/s; dt well below the contact durations.
MODELS = {
    "gran_hooke": dict(style="gran/hooke 2000 NULL 5.0e4 NULL 0.5 1", coeffs=["* *"]),
    "gran_hooke_history_limit_damping": dict(
        style="gran/hooke/history 2000 NULL 5.0e4 NULL 0.4 1 limit_damping", coeffs=["* *"]),
    "gran_hertz_history_dampflag0": dict(
        style="gran/hertz/history 4.0e7 NULL 5.0e4 NULL 0.3 0", coeffs=["* *"]),
    "gran_hertz_history_metal_units": dict(
        style="gran/hertz/history 4.0e9 3.0e9 5.0e4 NULL 0.3 1", coeffs=["* *"],
        units="metal", configs=["orthogonal"]),
    "granular_hooke_linear_history_velocity": dict(
        style="granular",
        coeffs=["* * hooke 2000 0.02 tangential linear_history 1500 0.5 0.5 damping velocity"]),
    "granular_hertz_material_mindlin_viscoelastic": dict(
        style="granular",
        coeffs=["* * hertz/material 1.0e8 1.0e9 0.3 tangential mindlin NULL 1.0 0.5 "
                "damping viscoelastic limit_damping"]),
    # The law the peer benchmark times (perf/peer/bench.lmp, hertz_tsuji), which the engine
    # runs as its own restitution-damped Hertz-Mindlin law (scenarios/lammps/native_laws.hpp).
    "granular_hertz_material_mindlin_tsuji": dict(
        style="granular",
        coeffs=["* * hertz/material 1.0e8 0.9 0.3 tangential mindlin NULL 0.5 0.5 damping tsuji"]),
    "granular_hertz_mindlin_mass_velocity": dict(
        style="granular",
        coeffs=["* * hertz 2.0e7 3.0e4 tangential mindlin 2.0e7 0.5 0.5 damping mass_velocity"]),
    "granular_two_types_tsuji_nohistory": dict(
        style="granular",
        coeffs=["1 1 hertz 3.0e7 0.8 tangential linear_nohistory 0.6 0.4 damping tsuji",
                "2 2 hertz 1.0e7 0.5 tangential linear_nohistory 0.4 0.6 damping tsuji",
                "1 2 hertz 2.0e7 0.6 tangential linear_nohistory 0.5 0.5 damping tsuji "
                "limit_damping"]),
}
CONFIGS = ["orthogonal", "triclinic", "dense"]
DT, STEPS = 5.0e-7, 40
COLUMNS = ["id", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz",
           "fx", "fy", "fz", "tx", "ty", "tz"]


def lammps_deck(model, data, units):
    coeffs = "\n".join("pair_coeff " + c for c in model["coeffs"])
    return f"""units {units}
atom_style sphere
boundary p p p
comm_modify vel yes
read_data {data}
pair_style {model['style']}
{coeffs}
neighbor 2.0e-4 bin
neigh_modify delay 0 every 1 check yes
fix 1 all nve/sphere
timestep {DT!r}
compute pv all pressure NULL pair
thermo_style custom step ke c_pv[1] c_pv[2] c_pv[3] c_pv[4] c_pv[5] c_pv[6]
thermo_modify format float %.17g
thermo {STEPS}
dump d all custom {STEPS} dump.txt id xu yu zu vx vy vz omegax omegay omegaz fx fy fz tqx tqy tqz
dump_modify d format float %.17g sort id
run {STEPS}
"""


def run_lammps(lmp, model, data, units, work):
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "in.lmp"), "w") as f:
        f.write(lammps_deck(model, data, units))
    p = subprocess.run([lmp, "-in", "in.lmp", "-log", "log.lammps", "-screen", "none"], cwd=work,
                       capture_output=True, text=True)
    if p.returncode != 0:
        log = open(os.path.join(work, "log.lammps")).read()[-3000:] if os.path.exists(
            os.path.join(work, "log.lammps")) else ""
        sys.exit(f"LAMMPS failed ({p.returncode}):\n{p.stdout[-2000:]}{p.stderr[-2000:]}{log}")
    # Normalised records: "thermo step ke p1..p6" and "atom step id x y z ... tz".
    out = []
    lines = open(os.path.join(work, "log.lammps")).read().splitlines()
    for k, line in enumerate(lines):
        if line.split()[:2] == ["Step", "KinEng"]:
            for row in lines[k + 1:]:
                w = row.split()
                if not w or not w[0].isdigit():
                    break
                out.append("thermo " + " ".join(w))
    for step, rows in read_dump(os.path.join(work, "dump.txt")).items():
        for i, values in rows.items():
            out.append(f"atom {step} {i} " + " ".join(repr(x) for x in values))
    return out


def parse_records(lines):
    thermo, atoms = {}, {}
    for line in lines:
        w = line.split()
        if w[0] == "thermo":
            thermo[int(w[1])] = [float(x) for x in w[2:]]
        elif w[0] == "atom":
            atoms.setdefault(int(w[1]), {})[int(w[2])] = [float(x) for x in w[3:]]
    return thermo, atoms


COLUMNS = ["xu", "yu", "zu", "vx", "vy", "vz", "omegax", "omegay", "omegaz", "fx", "fy", "fz",
           "tqx", "tqy", "tqz"]


def read_dump(path):
    """A LAMMPS dump file: {step: {id: [the COLUMNS' values]}}, by the ITEM headers."""
    lines = open(path).read().splitlines()
    frames, k = {}, 0
    while k < len(lines):
        if not lines[k].startswith("ITEM: TIMESTEP"):
            k += 1
            continue
        step = int(lines[k + 1])
        natoms = int(lines[k + 3])
        assert lines[k + 4].startswith("ITEM: BOX BOUNDS") and lines[k + 8].startswith("ITEM: ATOMS")
        names = lines[k + 8].split()[2:]
        at = [names.index(c) for c in COLUMNS]
        rows = {}
        for row in lines[k + 9:k + 9 + natoms]:
            w = row.split()
            rows[int(w[names.index("id")])] = [float(w[c]) for c in at]
        frames[step] = rows
        k += 9 + natoms
    return frames


def engine_records(out_dir, steps):
    import json
    summary = json.load(open(os.path.join(out_dir, "summary.json")))
    thermo, atoms = {}, {}
    for s in summary["states"]:
        thermo[s["step"]] = [s["kinetic_energy"]] + s["pair_pressure_tensor"]
    for step in (0, steps):
        frames = read_dump(os.path.join(out_dir, f"forces_step_{step}.lammpstrj"))
        atoms[step] = frames[step]
    return thermo, atoms


def normwise(a, b):
    """max |a - b| / max |b| over matching entries."""
    num = max(abs(x - y) for x, y in zip(a, b))
    den = max(abs(y) for y in b)
    return num / den if den > 0 else num


def compare(engine, ref, steps):
    """Relative errors per quantity and step."""
    (et, ea), (rt, ra) = engine, ref
    errors = {}
    for step in (0, steps):
        if set(ea[step]) != set(ra[step]):
            sys.exit(f"step {step}: atom ids differ between the engine and LAMMPS")
        ids = sorted(ra[step])
        groups = {"force": (9, 12), "torque": (12, 15), "velocity": (3, 6), "spin": (6, 9)}
        for name, (lo, hi) in groups.items():
            a = [ea[step][i][c] for i in ids for c in range(lo, hi)]
            b = [ra[step][i][c] for i in ids for c in range(lo, hi)]
            errors[f"{name}@{step}"] = normwise(a, b)
        if step > 0:
            a = [ea[step][i][c] - ea[0][i][c] for i in ids for c in range(3)]
            b = [ra[step][i][c] - ra[0][i][c] for i in ids for c in range(3)]
            errors[f"displacement@{step}"] = normwise(a, b)
        errors[f"pair_pressure@{step}"] = normwise(et[step][1:], rt[step][1:])
        errors[f"kinetic_energy@{step}"] = normwise(et[step][:1], rt[step][:1])
    return errors


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--granular", required=True)
    ap.add_argument("--model", required=True, choices=sorted(MODELS))
    ap.add_argument("--work", required=True)
    ap.add_argument("--lmp", default="")
    ap.add_argument("--perturb", type=float, default=0.0,
                    help="scale the engine's first pair_style number (kn) by 1 + this: the "
                         "comparison must then fail (it is not blind)")
    ap.add_argument("--write-refs", action="store_true",
                    help="store LAMMPS' output as the committed reference (needs --lmp)")
    args = ap.parse_args()
    model = MODELS[args.model]
    units = model.get("units", "si")
    failed, all_caught = False, True
    for config in model.get("configs", CONFIGS):
        case = f"{args.model}.{config}"
        work = os.path.join(args.work, case)
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        data = os.path.join(HERE, "data", f"{config}.data")
        ref_path = os.path.join(HERE, "reference", f"{case}.txt.gz")
        if args.lmp:
            live = run_lammps(args.lmp, model, data, units, os.path.join(work, "lammps"))
            if args.write_refs:
                with gzip.open(ref_path, "wt") as f:
                    f.write("\n".join(live) + "\n")
            elif os.path.exists(ref_path):
                stored = parse_records(gzip.open(ref_path, "rt").read().splitlines())
                drift = compare(stored, parse_records(live), STEPS)
                worst = max(drift.values())
                if worst > 1e-12:
                    print(f"{case}: this LAMMPS differs from the committed reference by "
                          f"{worst:.2e} (another version?); judged against this LAMMPS")
            ref = parse_records(live)
        else:
            if not os.path.exists(ref_path):
                sys.exit(f"{case}: no committed reference {ref_path} and no LAMMPS to run")
            ref = parse_records(gzip.open(ref_path, "rt").read().splitlines())
        coeffs = ", ".join('"' + c + '"' for c in model["coeffs"])
        style = model["style"]
        if args.perturb:
            w = style.split()
            w[1] = repr(float(w[1]) * (1 + args.perturb))
            style = " ".join(w)
        scene = os.path.join(work, "scene.toml")
        with open(scene, "w") as f:
            f.write(f"""scene = "lammps_forces"
[lammps]
data = "{data}"
units = "{units}"
pair_style = "{style}"
pair_coeff = [{coeffs}]
timestep = {DT!r}
[run]
steps = {STEPS}
""")
        out = os.path.join(work, "engine")
        p = subprocess.run([args.granular, "run", scene, "--out", out, "--quiet", "--threads", "1"],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"{case}: granular failed:\n{p.stdout}{p.stderr}")
        errors = compare(engine_records(out, STEPS), ref, STEPS)
        worst = max(errors, key=errors.get)
        ok = errors[worst] <= TOLERANCE
        failed |= not ok
        all_caught &= not ok
        print(f"{case}: largest relative difference {errors[worst]:.2e} ({worst}) "
              f"{'<=' if ok else '>'} {TOLERANCE:g}  [{'live LAMMPS' if args.lmp else 'committed LAMMPS output'}]")
        if not ok and not args.perturb:
            for k, v in sorted(errors.items()):
                print(f"    {k}: {v:.3e}")
    if args.perturb:  # every configuration must have told the perturbed run apart
        print("the perturbed run was " + ("not " if not all_caught else "") +
              "told apart in every configuration")
        sys.exit(0 if all_caught else 1)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
