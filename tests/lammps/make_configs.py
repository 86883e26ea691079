#!/usr/bin/python3
"""Writes the LAMMPS data files of the force-level comparison (atom style sphere, SI units):
64 spheres of two types on a jittered 4x4x4 lattice, d = 0.8-1.2 mm, with velocities and
spins, in three boxes:
  orthogonal  lattice spacing 0.9 mm: overlaps up to ~20 % of the mean diameter
  triclinic   the same lattice in a sheared box (xy, xz, yz tilts)
  dense       spacing 0.78 mm: overlaps up to ~35 % of the mean diameter
Deterministic (fixed seeds), so the committed files can be remade bit for bit.
Usage: make_configs.py OUTDIR"""
import random
import sys


def config(name, spacing, tilt, seed):
    rng = random.Random(seed)
    n = 4
    lx = ly = lz = n * spacing
    xy, xz, yz = (tilt[0] * lx, tilt[1] * lx, tilt[2] * ly)
    lines = [f"LAMMPS data file: force comparison, {name} box", "",
             f"{n ** 3} atoms", "2 atom types", "",
             f"0 {lx!r} xlo xhi", f"0 {ly!r} ylo yhi", f"0 {lz!r} zlo zhi"]
    if any(tilt):
        lines.append(f"{xy!r} {xz!r} {yz!r} xy xz yz")
    lines += ["", "Atoms # sphere", ""]
    vel = ["", "Velocities", ""]
    ids = list(range(1, n ** 3 + 1))
    rng.shuffle(ids)  # ids out of lattice order, listed in file order
    k = 0
    for i in range(n):
        for j in range(n):
            for m in range(n):
                s = [(i + 0.5 + rng.uniform(-0.12, 0.12)) / n,
                     (j + 0.5 + rng.uniform(-0.12, 0.12)) / n,
                     (m + 0.5 + rng.uniform(-0.12, 0.12)) / n]
                x = s[0] * lx + s[1] * xy + s[2] * xz
                y = s[1] * ly + s[2] * yz
                z = s[2] * lz
                t = 1 + (k % 2)
                d = rng.uniform(0.8e-3, 1.2e-3)
                rho = 2500.0 if t == 1 else 1200.0
                lines.append(f"{ids[k]} {t} {d!r} {rho!r} {x!r} {y!r} {z!r}")
                v = [rng.uniform(-0.3, 0.3) for _ in range(3)]
                w = [rng.uniform(-600.0, 600.0) for _ in range(3)]
                vel.append(f"{ids[k]} " + " ".join(repr(c) for c in v + w))
                k += 1
    return "\n".join(lines + vel) + "\n"


if __name__ == "__main__":
    out = sys.argv[1]
    for name, spacing, tilt, seed in [("orthogonal", 0.9e-3, (0, 0, 0), 1),
                                      ("triclinic", 0.9e-3, (0.3, -0.2, 0.25), 2),
                                      ("dense", 0.78e-3, (0, 0, 0), 3)]:
        with open(f"{out}/{name}.data", "w") as f:
            f.write(config(name, spacing, tilt, seed))
