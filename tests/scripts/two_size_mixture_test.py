#!/usr/bin/python3
"""scripts/two_size_mixture.py: the gas it writes has the asked soft volume fraction and the
solid volume of --solid-beads stiff beads, diameters within their ranges, no two beads
overlapping (brute force over periodic images), and `mixture_moduli` reads it as its packing
(`granular check` with particles.from on a scene that names the file).

    two_size_mixture_test.py GRANULAR"""
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "two_size_mixture.py"


def check(cond, what):
    if not cond:
        sys.exit(f"FAILED: {what}")


def main():
    granular = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "gas.h5"
        subprocess.run([sys.executable, str(SCRIPT), str(out), "--soft-fraction", "0.3",
                        "--solid-beads", "60", "--seed", "3"], check=True, capture_output=True)
        with h5py.File(out, "r") as f:
            g = f["final_state"]
            x, r, sp = g["position"][()], g["radius"][()], g["species"][()]
            edge = g["box_len"][()]
        check(np.all(edge == edge[0]), "a cube")
        d = 2 * r
        check(np.all((d[sp == 0] >= 3.8) & (d[sp == 0] <= 4.2)), "stiff diameters in range")
        check(np.all((d[sp == 1] >= 1.9) & (d[sp == 1] <= 2.1)), "soft diameters in range")
        v = r ** 3
        soft = v[sp == 1].sum() / v.sum()
        check(abs(soft - 0.3) < 0.02, f"soft volume fraction {soft} for 0.3")
        solid = 4 / 3 * math.pi * v.sum()
        check(abs(solid / (60 * math.pi / 6 * 4.0 ** 3 * (1 + 0.05 ** 2 / 3)) - 1) < 0.05,
              "the solid volume of 60 stiff beads")
        check(abs(solid / edge[0] ** 3 - 0.3) < 1e-9, "volume fraction 0.3")
        dx = x[:, None, :] - x[None, :, :]
        dx -= edge[0] * np.round(dx / edge[0])
        dist = np.sqrt((dx ** 2).sum(-1))
        gap = dist - (r[:, None] + r[None, :])
        np.fill_diagonal(gap, 1.0)
        check(gap.min() >= 0, f"no overlaps (smallest gap {gap.min()})")
        scene = (ROOT / "scenarios" / "waves" / "mixture_moduli_quick.toml").read_text()
        head, _, rest = scene.partition("[particles]\n")
        _, _, rest = rest.partition("\n\n")
        scene = (head + f'[particles]\nfrom = "{out}"\nfrom_materials = ["glass", "rubber"]\n\n'
                 + rest)
        scene = "\n".join(l for l in scene.splitlines()
                          if not l.startswith(("soft_volume_fractions", "phi_gas")))
        scene = scene.split("[pair_rule_check]")[0] + "[run]" + scene.split("[run]")[1]
        toml = Path(tmp) / "from_file.toml"
        toml.write_text(scene)
        p = subprocess.run([granular, "check", str(toml)], capture_output=True, text=True)
        check(p.returncode == 0, f"granular check: {p.stdout}{p.stderr}")
    print("two_size_mixture: OK")


if __name__ == "__main__":
    main()
