#!/usr/bin/env python3
"""A simple-shear cell between two rough walls, a protocol no scene driver has.

Spheres are confined between a floor and a lid (periodic in x and y); the lid is pushed down
until the normal stress reaches its target, the packing settles, and the lid then slides
along x at a constant height. The walls carry the particles' friction, so the lid drags the
packing into simple shear. The run reports the shear and normal stress on both walls and the
effective friction tau / sigma in steady flow; the sample's momentum balance (the two walls'
shear forces equal and opposite on average) checks the measurement.

    PYTHONPATH=build/python /usr/bin/python3 examples/simple_shear_walls.py --quick

Units: mm, us, ug (forces in N, stresses in MPa). Linear spring-dashpot contacts with Coulomb
friction; the shear rate is set by an inertial number I = gamma_dot d sqrt(rho / sigma).
"""
import argparse
import json
import os

import granular


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="400 particles, shear strain 0.5")
    ap.add_argument("--out", default="out/simple_shear_walls")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--inertial-number", type=float, default=1e-2)
    a = ap.parse_args()
    granular.initialize(a.threads)
    os.makedirs(a.out, exist_ok=True)

    n = 400 if a.quick else 3000
    shear_strain = 0.5 if a.quick else 2.0
    sigma = 1.0  # MPa, target normal stress
    d, rho, mu = 1.0, 2500.0, 0.5
    contact = {"normal": "linear", "kn": 1e4, "gamma_n": 1000.0, "tangential": "coulomb",
               "kt": 8e3, "mu": mu}
    # 1. A periodic packing compressed isotropically to just below jamming, with background
    #    damping; then z is closed by a floor and a lid at the box faces, the particles that
    #    straddle them removed, and the lid brought to sigma by a servo (the preparation keeps
    #    the damping; the shear runs without it, on a restart of the prepared state).
    prep = dict(dt=0.02, skin=0.2, damping=20.0, rotational_damping=5.0)
    pack = granular.random_packing(n, 0.8 * d, 1.2 * d, density=rho, phi=0.3, seed=a.seed)
    sim = granular.System(pack, contact=contact, **prep)
    sim.strain_to_phi(0.575, -2e-4, every=500)
    sim.relax(1e-3, 5000)
    p = sim.packing()
    lo, ln = list(p.box_lo), list(p.box_len)
    z, r = p.positions[:, 2], p.radius
    keep = (z - r >= lo[2]) & (z + r <= lo[2] + ln[2])
    cell = granular.Packing(p.positions[keep], r[keep], p.density[keep], box_len=ln, box_lo=lo)
    cell.velocities = p.velocities[keep]
    cell.periodic = (True, True, False)
    n = int(keep.sum())
    sim = granular.System(cell, contact=contact, **prep)
    floor = {"name": "floor", "normal": (0, 0, -1), "point": (0, 0, lo[2])}
    area = ln[0] * ln[1]
    z_top = lo[2] + ln[2]
    v_servo = 1e-3

    def lid(z, velocity):
        return {"name": "lid", "normal": (0, 0, 1), "point": (0, 0, z), "velocity": velocity}

    def lid_stress():
        return sim.wall_loads()[1]["force"][2] / area

    sim.set_walls([floor, lid(z_top, (0, 0, 0))])
    # 2. Servo: every check the lid moves by half the strain that would close the stress
    #    error at a modulus estimated from the contacts (0.3 kn / d), at most v_servo; the
    #    packing is ready when the normal stress has held at sigma (within 3 %) for five
    #    checks in a row. The same servo holds sigma during the shear.
    modulus = 0.3 * contact["kn"] / d

    def servo_speed(every):
        strain = 0.5 * (sigma - lid_stress()) / modulus
        return max(-v_servo, min(v_servo, -strain * (z_top - lo[2]) / (every * sim.dt)))

    held, checks, every = 0, 0, 500
    while held < 5:
        v = servo_speed(every)
        sim.set_walls([floor, lid(z_top, (0, 0, v))])
        sim.run(every)
        z_top += v * every * sim.dt
        held = held + 1 if abs(1.0 - lid_stress() / sigma) < 0.03 else 0
        checks += 1
        if checks > 4000:
            raise SystemExit("the lid servo did not hold sigma = %g MPa" % sigma)
    sim = granular.System.from_saved(sim.save(), contact=contact, dt=0.02, skin=0.2)
    sim.set_walls([floor, lid(z_top, (0, 0, 0))])
    height = z_top - lo[2]

    # 3. Shear at constant normal stress: the lid slides along x at the speed that gives the
    #    inertial number, and moves along z by the servo (the packing dilates as it shears).
    gamma_dot = a.inertial_number / (d * (rho / sigma) ** 0.5)
    v_lid = gamma_dot * height
    total = int(shear_strain / gamma_dot / sim.dt)
    every = max(1, total // 200)
    series = []
    start = sim.steps
    while sim.steps - start < total:
        v = servo_speed(every)
        sim.set_walls([floor, lid(z_top, (v_lid, 0, v))])
        sim.run(every)
        z_top += v * every * sim.dt
        f_floor, f_lid = (w["force"] for w in sim.wall_loads())
        series.append({
            "strain": v_lid * (sim.steps - start) * sim.dt / height, "gap": z_top - lo[2],
            "tau_lid": f_lid[0] / area, "tau_floor": -f_floor[0] / area,
            "sigma_lid": f_lid[2] / area, "sigma_floor": -f_floor[2] / area})

    steady = [r for r in series if r["strain"] >= 0.5 * shear_strain]
    mean = {k: sum(r[k] for r in steady) / len(steady) for k in steady[0]
            if k not in ("strain", "gap")}
    # Friction on the lid opposes its motion: the force on the lid is along -x.
    mu_eff = -mean["tau_lid"] / mean["sigma_lid"]
    result = {"particles": n, "height": height, "sigma": sigma,
              "inertial_number": a.inertial_number, "shear_rate": gamma_dot,
              "steady_means": mean, "effective_friction": mu_eff,
              "momentum_imbalance": (mean["tau_lid"] - mean["tau_floor"]) / abs(mean["tau_lid"]),
              "series": series}
    with open(os.path.join(a.out, "simple_shear_walls.json"), "w") as f:
        json.dump(result, f, indent=2)
    print("gap %.2f mm, sigma %.3f MPa, I %.0e: effective friction %.3f (particle mu %.2f); "
          "lid and floor shear stress %.4f / %.4f MPa" %
          (height, mean["sigma_lid"], a.inertial_number, mu_eff, mu, -mean["tau_lid"],
           -mean["tau_floor"]))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    g = [r["strain"] for r in series]
    ax.plot(g, [-r["tau_lid"] / max(r["sigma_lid"], 1e-300) for r in series], label="lid")
    ax.plot(g, [-r["tau_floor"] / max(r["sigma_floor"], 1e-300) for r in series], label="floor",
            alpha=0.7)
    ax.axhline(mu_eff, color="k", lw=0.8, ls="--", label="steady mean %.3f" % mu_eff)
    ax.set_xlabel("shear strain"), ax.set_ylabel("tau / sigma"), ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "simple_shear_walls.png"), dpi=120)


if __name__ == "__main__":
    main()
