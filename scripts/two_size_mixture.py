#!/usr/bin/python3
"""Writes a random gas of two materials with their own sizes, as a state group that
`mixture_moduli` (`particles.from`, species 0 then 1 through `particles.from_materials`) and
`wave_transmission` (`column.from`) start from: a study of mixtures whose soft beads are smaller
or larger than the stiff ones, which the scenes' own gas (one size distribution) cannot draw.

    scripts/two_size_mixture.py OUT.h5 --soft-fraction 0.2 [--stiff-diameter 3.8 4.2]
        [--soft-diameter 1.9 2.1] [--solid-beads 1000] [--phi 0.3] [--seed 1]

The soft beads take the volume fraction --soft-fraction of the solid; the solid volume is that of
--solid-beads stiff beads of the mean stiff size, so runs at different fractions and sizes hold
the same amount of material. Diameters are uniform in each range (mm). Beads are placed by
random sequential insertion (the largest first) in a periodic cube at the volume fraction --phi,
at rest. The group /final_state holds position, velocity, radius and species (0 stiff, 1 soft)
in mm and mm/us, box_lo and box_len, as the engine's state groups do (docs/data_formats.md).
"""
import argparse
import math
import sys

import numpy as np


def place(diameters, edge, rng):
    """Random sequential insertion of spheres of the given diameters (largest first)."""
    order = np.argsort(-diameters, kind="stable")
    centres = np.empty((len(diameters), 3))
    radii = np.empty(len(diameters))
    placed = 0
    for k in order:
        r = 0.5 * diameters[k]
        for _ in range(100000):
            c = rng.uniform(0.0, edge, 3)
            d = centres[:placed] - c
            d -= edge * np.round(d / edge)  # nearest periodic image
            if placed == 0 or np.all(np.einsum("ij,ij->i", d, d) >= (radii[:placed] + r) ** 2):
                break
        else:
            sys.exit("random insertion jammed: lower --phi")
        centres[placed], radii[placed] = c, r
        placed += 1
    return centres, radii, order


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--soft-fraction", type=float, required=True)
    ap.add_argument("--stiff-diameter", type=float, nargs=2, default=[3.8, 4.2])
    ap.add_argument("--soft-diameter", type=float, nargs=2, default=[1.9, 2.1])
    ap.add_argument("--solid-beads", type=int, default=1000)
    ap.add_argument("--phi", type=float, default=0.3)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    if not 0 <= a.soft_fraction <= 1:
        sys.exit("--soft-fraction must lie in [0, 1]")
    if not 0 < a.phi <= 0.4:
        sys.exit("--phi must lie in (0, 0.4]: random insertion jams above")

    def mean_volume(lo, hi):  # <d^3> of a uniform distribution, times pi/6
        return math.pi / 6 * (hi ** 4 - lo ** 4) / (4 * (hi - lo)) if hi > lo else math.pi / 6 * lo ** 3

    solid = a.solid_beads * mean_volume(*a.stiff_diameter)
    n_stiff = round((1 - a.soft_fraction) * solid / mean_volume(*a.stiff_diameter))
    n_soft = round(a.soft_fraction * solid / mean_volume(*a.soft_diameter))
    rng = np.random.default_rng(a.seed)
    d = np.concatenate([rng.uniform(*a.stiff_diameter, n_stiff), rng.uniform(*a.soft_diameter, n_soft)])
    species = np.concatenate([np.zeros(n_stiff, dtype=np.int32), np.ones(n_soft, dtype=np.int32)])
    edge = (math.pi / 6 * np.sum(d ** 3) / a.phi) ** (1 / 3)
    centres, radii, order = place(d, edge, rng)

    import h5py
    with h5py.File(a.out, "w") as f:
        g = f.create_group("final_state")
        g["position"] = centres
        g["velocity"] = np.zeros_like(centres)
        g["radius"] = radii
        g["species"] = species[order]
        g["box_lo"] = np.zeros(3)
        g["box_len"] = np.full(3, edge)
        g.attrs["density"] = 1.0  # the scenes take each material's own
        for name, unit in (("position", "mm"), ("velocity", "mm us-1"), ("radius", "mm"),
                           ("species", "1"), ("box_lo", "mm"), ("box_len", "mm")):
            g[name].attrs["unit"] = unit
    soft_volume = np.sum(radii[species[order] == 1] ** 3) / np.sum(radii ** 3)
    print(f"{a.out}: {n_stiff} stiff + {n_soft} soft beads, soft volume fraction "
          f"{soft_volume:.4f}, box edge {edge:.3f} mm")


if __name__ == "__main__":
    main()
