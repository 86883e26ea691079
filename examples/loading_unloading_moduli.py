#!/usr/bin/env python3
"""Moduli on the loading and the unloading branch of a glass-bead packing, a protocol no
scene driver has: a servo sequence up and back down in pressure, probing K, G and M at every
stop from a copy of the state (which the probe leaves untouched).

Along a loading path the packing gains contacts as it is compressed; on unloading it keeps
most of them, so at equal pressure the unloading branch is stiffer. The difference separates
the two parts of the pressure dependence M ~ P^n: the growth of the contact network and the
stiffening of the contacts already there.

    PYTHONPATH=build/python /usr/bin/python3 examples/loading_unloading_moduli.py --quick

Units: mm, us, ug; stresses and moduli in MPa. The glass is the source's (E = 63 GPa,
nu = 0.23, density 2500 kg/m^3, friction 0.3, restitution 0.9; docs/model_mixtures_and_waves.md).
"""
import argparse
import time
import json
import math
import os

import granular


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="300 particles, three pressures")
    ap.add_argument("--out", default="out/loading_unloading_moduli")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--seed", type=int, default=5)
    a = ap.parse_args()
    granular.initialize(a.threads)
    os.makedirs(a.out, exist_ok=True)

    n = 300 if a.quick else 2000
    up = [1.0, 3.0, 10.0] if a.quick else [0.1, 0.3, 1.0, 3.0, 10.0]
    path = up + up[-2::-1]  # up, then back down through the same stops
    materials = {"glass": {"young_modulus": 63e3, "poisson": 0.23, "density": 2500.0,
                           "friction": 0.3, "restitution": 0.9}}
    t0 = time.time()
    pack = granular.random_packing(n, 0.8, 1.2, density=2500.0, phi=0.3, seed=a.seed, speed=1e-4)
    settings = dict(dt=2e-3, skin=0.1, damping=50.0, rotational_damping=10.0)
    # Dense preparation: compressed without friction just past jamming and briefly relaxed,
    # then friction switched on (the saved state restarted under the frictional law).
    sim = granular.System(pack, materials=materials, contact={"tangential": "none"}, **settings)
    sim.strain_to_phi(0.64, -1e-3, every=500)
    sim.relax(1e-3, 20000)
    sim = granular.System.from_saved(sim.save(), materials=materials,
                                     contact={"tangential": "mindlin"}, **settings)
    print("%6.1f s prepared" % (time.time() - t0))
    stops = []
    for k, p in enumerate(path):
        servo = sim.servo_to_pressure(p, ekin_ratio=1e-5)
        m = servo["measurements"]
        if not servo["converged"]:  # never probe a state the servo did not reach
            raise SystemExit("servo stopped at %.4g MPa short of %g" % (m["pressure"], p))
        mod = sim.probe_moduli(1e-6, 1500, 1500)
        branch = "loading" if k < len(up) else "unloading"
        stops.append({"branch": branch, "pressure": m["pressure"], "phi": m["phi"],
                      "z_corrected": m["z_corrected"], "contacts": m["contacts"],
                      "K": mod["K"], "G": mod["G"], "M": mod["M"]})
        print("%6.1f s " % (time.time() - t0), end="")
        print("%-9s P %.3f MPa  phi %.4f  Z %.2f  K %.0f  G %.0f  M %.0f MPa" %
              (branch, m["pressure"], m["phi"], m["z_corrected"], mod["K"], mod["G"], mod["M"]))

    def exponent(rows):
        """Least-squares slope of log M against log P."""
        xs = [math.log(r["pressure"]) for r in rows]
        ys = [math.log(r["M"]) for r in rows]
        xm, ym = sum(xs) / len(xs), sum(ys) / len(ys)
        return sum((x - xm) * (y - ym) for x, y in zip(xs, ys)) / sum((x - xm) ** 2 for x in xs)

    loading = [s for s in stops if s["branch"] == "loading"]
    unloading = [s for s in stops if s["branch"] == "unloading"] + [loading[-1]]
    result = {"particles": n, "stops": stops, "n_loading": exponent(loading),
              "n_unloading": exponent(unloading)}
    with open(os.path.join(a.out, "loading_unloading_moduli.json"), "w") as f:
        json.dump(result, f, indent=2)
    print("M ~ P^n: n = %.3f loading, %.3f unloading" % (result["n_loading"], result["n_unloading"]))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(1, 2, figsize=(9, 4))
    for branch, style in (("loading", "o-"), ("unloading", "s--")):
        rows = [s for s in stops if s["branch"] == branch]
        if branch == "unloading":
            rows = [loading[-1]] + rows
        ax[0].loglog([r["pressure"] for r in rows], [r["M"] for r in rows], style, label=branch)
        ax[1].semilogx([r["pressure"] for r in rows], [r["z_corrected"] for r in rows], style,
                       label=branch)
    ax[0].set_xlabel("P (MPa)"), ax[0].set_ylabel("M (MPa)"), ax[0].legend()
    ax[1].set_xlabel("P (MPa)"), ax[1].set_ylabel("Z without rattlers"), ax[1].legend()
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "loading_unloading_moduli.png"), dpi=120)


if __name__ == "__main__":
    main()
