"""The examples in examples/, each a protocol no scene driver has, run in their quick form;
each result is held to a law it must obey."""
import json
import os
import subprocess
import sys

import pytest

from conftest import BUILD, REPO


def run_example(name, out):
    env = dict(os.environ, PYTHONPATH=os.path.join(BUILD, "python"))
    subprocess.run([sys.executable, os.path.join(REPO, "examples", name + ".py"), "--quick",
                    "--threads", "2", "--out", str(out)], check=True, env=env)
    with open(os.path.join(out, name + ".json")) as f:
        return json.load(f)


def test_cyclic_pure_shear_secant_modulus_meets_the_probe_and_softens_with_amplitude(tmp_path):
    r = run_example("cyclic_pure_shear", tmp_path)
    c = r["cycles"]
    # The smallest cycle is nearly elastic: its secant modulus is the probe's G.
    assert c[0]["G_secant"] == pytest.approx(r["probe"]["G"], rel=0.1)
    # Larger cycles slide more contacts: softer, and more dissipative per cycle.
    assert c[1]["G_secant"] < c[0]["G_secant"]
    assert c[1]["damping_ratio"] > c[0]["damping_ratio"]
    # A closed cycle cannot return energy (second law): the loop area is not negative.
    assert all(x["dissipated_energy_density"] > 0 for x in c)


def test_loading_branch_stiffens_with_pressure_between_the_hertz_bounds(tmp_path):
    r = run_example("loading_unloading_moduli", tmp_path)
    load = [s for s in r["stops"] if s["branch"] == "loading"]
    for key in ("K", "G", "M", "z_corrected"):
        assert all(a[key] < b[key] for a, b in zip(load, load[1:])), key
    # Hertz contacts on a fixed network give n = 1/3; contacts gained add to it.
    assert 1 / 3 - 0.03 < r["n_loading"] < 1.0


def test_simple_shear_cell_balances_momentum_between_its_walls(tmp_path):
    r = run_example("simple_shear_walls", tmp_path)
    m = r["steady_means"]
    # On average the sample does not accelerate: the two walls' forces balance, along the
    # shear and along the normal.
    assert abs(r["momentum_imbalance"]) < 0.05
    assert m["sigma_lid"] == pytest.approx(m["sigma_floor"], rel=0.05)
    # The lid's friction opposes its motion (positive dissipation).
    assert 0 < r["effective_friction"]
