#!/usr/bin/python3
"""scripts/two_size_mixture.py: the gas it writes has the asked soft volume fraction and the
solid volume of --solid-beads stiff beads, diameters within their ranges, no two beads
overlapping (brute force over periodic images), and `mixture_moduli` reads it as its packing
(`granular check` with particles.from on a scene that names the file). Then a run of
`mixture_moduli` on glass with a tenth of its volume in rubber beads a quarter its size: most
rubber beads rattle in the glass pores (over half of all beads), yet the state the servo
brings to rest at its pressure is jammed and probed (M > 0), not reported as a gas.

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

        small = Path(tmp) / "small_rubber.h5"
        subprocess.run([sys.executable, str(SCRIPT), str(small), "--soft-fraction", "0.1",
                        "--soft-diameter", "0.95", "1.05", "--solid-beads", "120"], check=True,
                       capture_output=True)
        text = scene.replace(str(out), str(small))
        text = text.replace("pressures = [0.1, 0.5, 2.0]", "pressures = [0.5]")
        text = text.replace("ekin_ratio = 1.0e-3", "ekin_ratio = 3.0e-3")
        toml.write_text(text)
        run_dir = Path(tmp) / "run"
        p = subprocess.run([granular, "run", str(toml), "--out", str(run_dir), "--threads", "1",
                            "--quiet"], capture_output=True, text=True)
        check(p.returncode == 0, f"granular run: {p.stdout}{p.stderr}")
        with h5py.File(run_dir / "results.h5", "r") as f:
            t = {k: f["table"][k][()] for k in ("servo_converged", "rattler_fraction", "jammed",
                                                  "probed", "M")}
        check(t["servo_converged"][0] == 1, "the servo brings the two-size packing to rest")
        check(t["rattler_fraction"][0] > 0.5, f"most beads rattle ({t['rattler_fraction'][0]})")
        check(t["jammed"][0] == 1 and t["probed"][0] == 1, "a state at its pressure is jammed")
        check(t["M"][0] > 0, f"and probed (M = {t['M'][0]})")
    print("two_size_mixture: OK")


if __name__ == "__main__":
    main()
