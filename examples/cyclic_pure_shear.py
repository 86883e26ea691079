#!/usr/bin/env python3
"""Cyclic pure shear of a frictional Hertz-Mindlin packing, a protocol no scene driver has.

The packing is brought to an isotropic pressure by the engine's servo, its moduli are probed,
then the box is sheared back and forth in pure shear (x compressed while y stretches, then the
reverse) for several cycles of growing amplitude. For every cycle it reports the secant shear
modulus between the turning points and the energy dissipated per unit volume (the area of the
stress-strain loop), with the equivalent damping ratio; the chart shows the loops.

    PYTHONPATH=build/python /usr/bin/python3 examples/cyclic_pure_shear.py --quick --out out/cyclic

Units: mm, us, ug (stresses in MPa). Strains e are compressive true strains of the x edge
(y takes -e); the shear stress is tau = (s_xx - s_yy) / 2 and the shear strain gamma = 2 e, so
the secant modulus is G = d tau / d gamma.
"""
import argparse
import json
import math
import os

import granular


def pure_shear_leg(sim, to_e, e_now, steps, every, record):
    """Strain from e_now to to_e in `steps` steps at a constant rate, sampling every `every`."""
    rate = (to_e - e_now) / (steps * sim.dt)  # compressive strain rate of x
    # Edge rates: L_x = L0 exp(-e), L_y = L0 exp(+e); expm1 keeps the strain per step exact.
    r = math.expm1(-rate * sim.dt) / sim.dt
    sim.strain_rate = (r, -r, 0.0)
    done = 0
    while done < steps:
        n = min(every, steps - done)
        sim.step(n)
        done += n
        e = e_now + (to_e - e_now) * done / steps
        m = sim.measure()
        record.append((e, m["stress"][0] - m["stress"][1], m["pressure"]))
    sim.strain_rate = (0.0, 0.0, 0.0)
    return to_e


def loop_measures(samples, amplitude):
    """Secant shear modulus and dissipated energy density of one closed cycle."""
    d_hi = max(samples, key=lambda s: s[0])[1]
    d_lo = min(samples, key=lambda s: s[0])[1]
    tau_a = (d_hi - d_lo) / 4.0  # half the swing of (s_xx - s_yy) / 2
    gamma_a = 2.0 * amplitude
    g_sec = tau_a / gamma_a
    # Work per unit volume, s_xx de_x + s_yy de_y = (s_xx - s_yy) de, around the loop.
    work = sum(0.5 * (a[1] + b[1]) * (b[0] - a[0]) for a, b in zip(samples, samples[1:]))
    w_elastic = 0.5 * tau_a * gamma_a
    return {"amplitude": amplitude, "G_secant": g_sec, "dissipated_energy_density": work,
            "damping_ratio": work / (4 * math.pi * w_elastic) if w_elastic > 0 else float("nan")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="300 particles, two amplitudes")
    ap.add_argument("--out", default="out/cyclic_pure_shear")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--seed", type=int, default=3)
    a = ap.parse_args()
    granular.initialize(a.threads)
    os.makedirs(a.out, exist_ok=True)

    n = 300 if a.quick else 2000
    amplitudes = [1e-5, 1e-4] if a.quick else [1e-6, 1e-5, 1e-4, 1e-3]
    pressure = 1.0  # MPa
    quarter = 1500 if a.quick else 4000  # steps per quarter cycle

    # A dense preparation: compressed and brought to the pressure without friction, then
    # friction switched on (a restart of the saved state under the frictional law) and the
    # pressure held again.
    pack = granular.random_packing(n, 1.0, 2.0, density=2000.0, phi=0.3, seed=a.seed, speed=1e-4)
    hertz = {"normal": "hertz", "shear_modulus": 29e3, "poisson": 0.2, "alpha_n": 1000.0}
    frictional = dict(hertz, tangential="coulomb", tangential_law="mindlin_stiffness",
                      alpha_t=20.0, mu=0.3)
    settings = dict(dt=0.004, skin=0.2, damping=100.0, rotational_damping=20.0)
    sim = granular.System(pack, contact=hertz, **settings)
    sim.strain_to_phi(0.63, -1e-3, every=500)
    sim.servo_to_pressure(pressure, tolerance=0.05, ekin_ratio=1e-4)
    sim = granular.System.from_saved(sim.save(), contact=frictional, **settings)
    servo = sim.servo_to_pressure(pressure, ekin_ratio=1e-6)
    if not servo["converged"]:
        raise SystemExit("the servo did not reach %g MPa (%d checks)" % (pressure, servo["cycles"]))
    probe = sim.probe_moduli(1e-6, 2000, 2000)
    state0 = sim.measure()

    cycles, loops = [], []
    for amp in amplitudes:
        rec = [(0.0, state0["stress"][0] - state0["stress"][1], state0["pressure"])]
        e = 0.0
        every = max(1, quarter // 50)
        for target in (amp, -amp, 0.0):  # up, down through zero, back: one closed cycle
            steps = quarter * (2 if target == -amp else 1)
            e = pure_shear_leg(sim, target, e, steps, every, rec)
        cycles.append(loop_measures(rec, amp))
        loops.append(rec)
        state0 = sim.measure()

    result = {
        "particles": n, "pressure_target": pressure, "servo": {
            "converged": servo["converged"], "pressure": servo["measurements"]["pressure"],
            "phi": servo["measurements"]["phi"], "z_corrected": servo["measurements"]["z_corrected"]},
        "probe": {"K": probe["K"], "G": probe["G"], "M": probe["M"]},
        "cycles": cycles,
    }
    with open(os.path.join(a.out, "cyclic_pure_shear.json"), "w") as f:
        json.dump(result, f, indent=2)
    for c in cycles:
        print("amplitude %.0e  G_secant %.1f MPa (probe G %.1f)  W %.3e mJ/mm^3  damping %.3f" %
              (c["amplitude"], c["G_secant"], probe["G"], c["dissipated_energy_density"],
               c["damping_ratio"]))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(1, len(loops), figsize=(4.5 * len(loops), 4), squeeze=False)
    for k, (rec, c) in enumerate(zip(loops, cycles)):
        ax[0][k].plot([2 * s[0] for s in rec], [s[1] / 2 for s in rec], lw=1)
        ax[0][k].set_xlabel("shear strain gamma = 2 e")
        ax[0][k].set_ylabel("shear stress (s_xx - s_yy)/2 (MPa)")
        ax[0][k].set_title("amplitude %.0e: G_sec %.0f MPa, xi %.3f" %
                           (c["amplitude"], c["G_secant"], c["damping_ratio"]), fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "cyclic_pure_shear.png"), dpi=120)


if __name__ == "__main__":
    main()
