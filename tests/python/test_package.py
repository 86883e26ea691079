"""The Python package against closed forms, the engine's own measures and the command line."""
import json
import math
import os
import subprocess
import threading

import h5py
import numpy as np
import pytest

from conftest import REPO


def two_spheres(granular, gap=0.0, speed=0.1, radius=0.5, density=2500.0):
    """Two equal spheres on the x axis approaching head-on with relative speed 2*speed."""
    x = np.array([[4.0 - radius - gap / 2, 5.0, 5.0], [6.0 + radius + gap / 2 - 2.0, 5.0, 5.0]])
    p = granular.Packing(x, np.full(2, radius), np.full(2, density), box_len=(10.0, 10.0, 10.0))
    p.velocities = np.array([[speed, 0, 0], [-speed, 0, 0]])
    return p


def test_linear_dashpot_collision_restitution_matches_closed_form(granular):
    # e = exp(-pi zeta / sqrt(1 - zeta^2)), zeta = gamma_n / (2 sqrt(m_eff kn)): the closed form
    # of the linear spring-dashpot; the engine's time stepping should meet it to O(dt).
    r, rho, kn, gn = 0.5, 2500.0, 1e4, 400.0
    m = rho * 4.0 / 3.0 * math.pi * r**3
    zeta = gn / (2 * math.sqrt(0.5 * m * kn))
    e_exact = math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))
    p = two_spheres(granular, gap=0.01, speed=0.05, radius=r, density=rho)
    sim = granular.System(p, contact={"normal": "linear", "kn": kn, "gamma_n": gn}, dt=1e-3,
                          skin=0.1)
    tc = math.pi / math.sqrt(2 * kn / m * (1 - zeta**2))
    sim.run(int((0.01 / 0.1 + 3 * tc) / 1e-3))
    v = sim.velocities()
    e = (v[1, 0] - v[0, 0]) / 0.1
    assert e == pytest.approx(e_exact, rel=2e-3)
    assert v[0, 0] + v[1, 0] == pytest.approx(0.0, abs=1e-15)  # momentum


def test_contact_network_reproduces_the_measured_stress_tensor(granular):
    # sigma = -(1/V) sum_c b (x) f_i over the contacts the network lists (b from i to j, f_i the
    # force on i) must equal the engine's own stress measure.
    pack = granular.random_packing(200, 0.8, 1.2, density=2500.0, phi=0.3, seed=4, speed=1e-3)
    sim = granular.System(pack, contact={"normal": "linear", "kn": 1e4, "gamma_n": 500.0,
                                         "tangential": "coulomb", "kt": 8e3, "mu": 0.4},
                          dt=0.02, skin=0.2)
    sim.strain_to_phi(0.66, -1e-3, every=200)
    sim.run(500)
    c = sim.contacts()
    assert len(c["i"]) > 200 and np.all(c["i"] < c["j"])
    b = c["branch"]
    n = -b / np.linalg.norm(b, axis=1)[:, None]  # from j towards i
    f = c["normal_force"][:, None] * n + c["tangential_force"]
    s = -np.einsum("ca,cb->ab", b, f) / np.prod(sim.box_len)
    m = sim.measure()
    ref = m["stress"]
    got = [s[0, 0], s[1, 1], s[2, 2], s[0, 1], s[0, 2], s[1, 2]]
    assert np.allclose(got, ref, rtol=1e-9, atol=1e-12 * abs(ref[0]))
    assert len(c["i"]) == m["contacts"]


def test_restarting_probe_leaves_the_state_untouched(granular):
    pack = granular.random_packing(150, 0.8, 1.2, density=2500.0, phi=0.3, seed=2)
    sim = granular.System(pack, contact={"normal": "hertz", "shear_modulus": 29e3,
                                         "poisson": 0.2, "alpha_n": 1000.0}, dt=2e-3, skin=0.2,
                          damping=50.0)
    sim.strain_to_phi(0.68, -1e-3, every=500)
    sim.relax(1e-6, 20000)
    before, x0 = sim.measure(), sim.positions()
    mod = sim.probe_moduli(1e-6, 500, 500)
    assert mod["K"] > 0 and mod["G"] > 0 and mod["M"] > mod["K"]
    assert sim.measure() == before
    assert np.array_equal(sim.positions(), x0)


def test_saved_state_restarts_the_same_from_memory_and_from_its_file(granular, tmp_path):
    pack = granular.random_packing(120, 0.8, 1.2, density=2500.0, phi=0.3, seed=6, speed=1e-3)
    contact = {"normal": "linear", "kn": 1e4, "gamma_n": 500.0, "tangential": "coulomb",
               "kt": 8e3, "mu": 0.4}
    sim = granular.System(pack, contact=contact, dt=0.02, skin=0.2)
    sim.strain_to_phi(0.64, -1e-3, every=200)
    state = sim.save(tmp_path / "state.h5")
    a = sim.restart(state)
    b = granular.System.from_saved(tmp_path / "state.h5", contact=contact, dt=0.02, skin=0.2)
    assert len(a.contacts()["i"]) == len(b.contacts()["i"]) > 0
    a.run(300)
    b.run(300)
    assert np.array_equal(a.positions(), b.positions())
    assert np.array_equal(a.forces(), b.forces())


def test_mixed_precision_compression_follows_the_double_one(granular):
    # precision="mixed" reads fixed-point positions in the force pass (docs/mixed_precision.md):
    # a short damped frictional compression (about 700 steps) ends within round-off levels of
    # the double run (measured 1.5e-9 apart), yet not on its bits (the switch reached the
    # engine). Longer runs part further, as any two runs a rounding apart do: over 13 000 steps
    # the pressures were 1e-3 apart.
    contact = {"normal": "linear", "kn": 1e4, "gamma_n": 500.0, "tangential": "coulomb",
               "kt": 8e3, "mu": 0.4}
    ends = []
    for precision in ("double", "mixed"):
        pack = granular.random_packing(300, 0.8, 1.2, density=2500.0, phi=0.3, seed=4, speed=1e-3)
        sim = granular.System(pack, contact=contact, dt=0.02, skin=0.2, precision=precision)
        sim.strain_to_phi(0.64, -2e-2, every=100)
        sim.run(300)
        ends.append(sim.measure())
    assert ends[0]["contacts"] > 300
    assert ends[1]["pressure"] == pytest.approx(ends[0]["pressure"], rel=1e-6)
    assert ends[1]["pressure"] != ends[0]["pressure"]


def test_unknown_precision_is_refused_naming_the_choices(granular):
    pack = granular.random_packing(10, 0.8, 1.2, density=2500.0, phi=0.1)
    with pytest.raises(granular.InputError, match='precision must be "double" or "mixed"'):
        granular.System(pack, contact={"normal": "linear", "kn": 1e4}, dt=0.01, skin=0.1,
                        precision="single")


def test_misspelt_contact_key_is_refused_naming_it(granular):
    pack = granular.random_packing(10, 0.8, 1.2, density=2500.0, phi=0.1)
    with pytest.raises(granular.InputError, match="contact.gama_n"):
        granular.System(pack, contact={"normal": "linear", "kn": 1e4, "gama_n": 1.0}, dt=0.01,
                        skin=0.1)


def test_time_step_too_large_for_the_contact_is_refused(granular):
    pack = granular.random_packing(10, 0.8, 1.2, density=2500.0, phi=0.1)
    with pytest.raises((granular.InputError, granular.PhysicsError), match="dt"):
        granular.System(pack, contact={"normal": "linear", "kn": 1e4}, dt=1.0, skin=0.1)


def test_stepping_releases_the_gil(granular):
    # Kokkos' OpenMP backend takes work from the thread that started it, so the main thread
    # steps; a Python thread counts while it does, which it can only do without the GIL.
    pack = granular.random_packing(2000, 0.8, 1.2, density=2500.0, phi=0.3, seed=1, speed=1e-2)
    sim = granular.System(pack, contact={"normal": "linear", "kn": 1e4}, dt=0.01, skin=0.2)
    ticks, stop = [], threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)
            stop.wait(0.001)

    t = threading.Thread(target=count)
    t.start()
    try:
        sim.step(3000)
    finally:
        stop.set()
        t.join()
    assert len(ticks) > 10


def test_scene_run_from_python_gives_the_command_lines_bits(granular, binary, tmp_path):
    scene = os.path.join(REPO, "scenarios", "collisions", "two_particle_linear.toml")
    cli, py = tmp_path / "cli", tmp_path / "py"
    env = dict(os.environ, OMP_NUM_THREADS="2")
    subprocess.run([binary, "run", scene, "--out", str(cli), "--threads", "2", "--quiet"],
                   check=True, env=env, capture_output=True)
    granular.run_scene(scene, py)
    with open(cli / "summary.json") as f:
        a = json.load(f)
    with open(py / "summary.json") as f:
        b = json.load(f)
    a.pop("run"), b.pop("run")  # the run record: wall time, host, threads
    assert a == b
    with h5py.File(cli / "results.h5") as fa, h5py.File(py / "results.h5") as fb:
        names = []
        fa.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
        assert names
        for n in names:
            assert np.array_equal(fa[n][()], fb[n][()]), n
