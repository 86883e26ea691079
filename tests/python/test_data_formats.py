"""Files other tools read: LAMMPS data and dump files read back by LAMMPS itself, and the
snapshot series' H5MD file read by h5py and MDAnalysis, each against the engine's values."""
import os
import re
import shutil
import subprocess

import h5py
import numpy as np
import pytest

from conftest import REPO

LMP = shutil.which("lmp")


def small_system(granular, n=60):
    pack = granular.random_packing(n, 0.8, 1.2, density=2500.0, phi=0.3, seed=9, speed=1e-2)
    sp = np.arange(n) % 2
    pack.species = sp
    sim = granular.System(pack, contact={"normal": "linear", "kn": 1e4, "gamma_n": 100.0,
                                         "tangential": "coulomb", "kt": 8e3, "mu": 0.4},
                          dt=0.01, skin=0.2)
    sim.run(500)
    return sim


def lammps_dump_rows(path):
    """{id: row} of the last frame of a dump, with its column names."""
    lines = open(path).read().splitlines()
    k = max(i for i, l in enumerate(lines) if l.startswith("ITEM: TIMESTEP"))
    n = int(lines[k + 3])
    cols = lines[k + 8].split()[2:]
    rows = {}
    for line in lines[k + 9:k + 9 + n]:
        w = line.split()
        rows[int(w[0])] = dict(zip(cols, map(float, w)))
    return rows


def run_lammps(work, deck):
    with open(os.path.join(work, "in.lmp"), "w") as f:
        f.write(deck)
    p = subprocess.run([LMP, "-in", "in.lmp", "-log", "log.lammps", "-screen", "none"],
                       cwd=work, capture_output=True, text=True)
    assert p.returncode == 0, open(os.path.join(work, "log.lammps")).read()[-2000:]


def test_lammps_data_file_reads_back_in_the_engine(granular, tmp_path):
    sim = small_system(granular)
    pack = sim.packing()
    granular.write_lammps_data(pack, tmp_path / "data.lmp")
    back = granular.read_lammps_data(tmp_path / "data.lmp")
    for name in ("positions", "velocities", "angular_velocities", "radius", "density"):
        assert np.allclose(getattr(back, name), getattr(pack, name), rtol=1e-15, atol=0), name
    assert np.array_equal(back.species, pack.species)
    assert np.allclose(back.box_len, pack.box_len, rtol=1e-15)


@pytest.mark.skipif(LMP is None, reason="LAMMPS (Debian's lammps package) is not installed")
def test_lammps_reads_the_data_and_dump_files_with_the_engines_values(granular, tmp_path):
    sim = small_system(granular)
    pack = sim.packing()
    granular.write_lammps_data(pack, tmp_path / "data.lmp")
    sim.write_lammps_dump(tmp_path / "state.lammpstrj")
    step = sim.steps
    # LAMMPS reads the data file, writes what it holds; then replaces positions and
    # velocities from the engine's dump (read_dump) and writes them again.
    run_lammps(tmp_path, f"""units si
atom_style sphere
boundary p p p
read_data data.lmp
write_dump all custom from_data.txt id type radius x y z vx vy vz omegax omegay omegaz modify format float %.17g sort id
displace_atoms all move 1e-4 0 0 units box
read_dump state.lammpstrj {step} x y z vx vy vz box yes
write_dump all custom from_dump.txt id x y z vx vy vz modify format float %.17g sort id
""")
    data = lammps_dump_rows(tmp_path / "from_data.txt")
    dump = lammps_dump_rows(tmp_path / "from_dump.txt")
    ours = lammps_dump_rows(tmp_path / "state.lammpstrj")
    assert len(data) == len(dump) == len(ours) == pack.size
    for i, row in ours.items():
        for c in ("type", "radius", "x", "y", "z", "vx", "vy", "vz", "omegax", "omegay",
                  "omegaz"):
            assert data[i][c] == pytest.approx(row[c], rel=1e-14, abs=1e-300), (i, c)
        for c in ("x", "y", "z", "vx", "vy", "vz"):
            assert dump[i][c] == pytest.approx(row[c], rel=1e-14, abs=1e-300), (i, c)


def set_key(text, table, key, value):
    """The scene text with key = value in [table]."""
    head = text.index("[%s]" % table)
    end = text.find("\n[", head + 1)
    end = len(text) if end < 0 else end
    body = text[head:end]
    line = re.compile(r"^%s\s*=.*$" % re.escape(key), re.M)
    body = line.sub("%s = %s" % (key, value), body) if line.search(body) else \
        body.rstrip("\n") + "\n%s = %s\n" % (key, value)
    return text[:head] + body + text[end:]


def test_snapshot_series_h5md_holds_the_frames_with_box_and_units(granular, tmp_path):
    text = open(os.path.join(REPO, "scenarios", "packings", "isotropic_compression.toml")).read()
    for table, key, value in (("particles", "count", 200), ("compression", "phi_end", 0.62),
                              ("compression", "volumetric_strain_rate", 5e-3),
                              ("compression", "relax_steps", 1000),
                              ("output", "snapshot_every", 2000),
                              ("output", "snapshot_contacts", "true")):
        text = set_key(text, table, key, value)
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    granular.run_scene(scene, tmp_path / "out")
    out = tmp_path / "out"
    with h5py.File(out / "snapshots.h5md") as f, h5py.File(out / "snapshots.h5") as s:
        assert list(f["h5md"].attrs["version"]) == [1, 1]
        p = f["particles/all"]
        assert [b.decode() for b in p["box"].attrs["boundary"]] == ["periodic"] * 3
        assert p["position/value"].attrs["unit"] == "mm"
        assert p["position/time"].attrs["unit"] == "us"
        assert p["force/value"].attrs["unit"] == "N"
        steps = list(p["position/step"][()])
        frames = sorted(k for k in s if k.startswith("step_"))
        assert len(steps) == len(frames) > 2
        for k, name in enumerate(frames):
            g = s[name]
            assert steps[k] == int(g.attrs["step"])
            assert p["position/time"][k] == g.attrs["time"]
            assert np.array_equal(p["position/value"][k], g["position"][()])
            assert np.array_equal(p["velocity/value"][k], g["velocity"][()])
            assert np.array_equal(p["force/value"][k], g["force"][()])
            assert np.array_equal(p["box/edges/value"][k], np.diag(g["box_len"][()]))
        # The box shrinks as the packing is compressed: one box per frame.
        edges = p["box/edges/value"][()]
        assert edges[-1][0][0] < edges[0][0][0]
        assert np.array_equal(p["radius"][()], s[frames[0]]["radius"][()])
        # The last frame's contact network: as many contacts as the run counted, and the
        # stress rebuilt from them, -(1/V) sum b (x) f, is the run's final stress.
        last = s[frames[-1]]
        c = last["contacts"]
        b = c["branch"][()]
        n = -b / np.linalg.norm(b, axis=1)[:, None]
        f = c["normal_force"][()][:, None] * n + c["tangential_force"][()]
        sigma = -np.einsum("ca,cb->ab", b, f) / np.prod(last["box_len"][()])
        with h5py.File(out / "results.h5") as r:
            series = r["series"]
            assert len(b) == round(series["z"][-1] * 200 / 2)
            for a, name in enumerate(("stress_xx", "stress_yy", "stress_zz")):
                assert sigma[a, a] == pytest.approx(series[name][-1], rel=1e-9)
        assert np.all(c["pair"][()][:, 0] < c["pair"][()][:, 1])


def test_mdanalysis_reads_the_h5md_series_and_the_dump(granular, tmp_path):
    mda = pytest.importorskip("MDAnalysis")
    from MDAnalysis.coordinates.H5MD import H5MDReader
    test_snapshot_series_h5md_holds_the_frames_with_box_and_units(granular, tmp_path)
    path = tmp_path / "out" / "snapshots.h5md"
    # MDAnalysis' H5MD reader knows molecular units only (A, nm, ps; no mm or us) and refuses
    # the file's unit strings even with convert_units=False: it reads a copy without them.
    plain = tmp_path / "plain.h5md"
    shutil.copy(path, plain)
    with h5py.File(plain, "r+") as f:
        f.visititems(lambda n, o: o.attrs.__delitem__("unit") if "unit" in o.attrs else None)
        pos = f["particles/all/position/value"][()]
        vel = f["particles/all/velocity/value"][()]
        edges = f["particles/all/box/edges/value"][()]
        time = f["particles/all/position/time"][()]
    r = H5MDReader(str(plain), convert_units=False)
    assert r.n_frames == len(pos) and r.n_atoms == pos.shape[1]
    for k, ts in enumerate(r):
        assert np.allclose(ts.positions, pos[k], rtol=1e-6)  # MDAnalysis keeps float32
        assert np.allclose(ts.velocities, vel[k], rtol=1e-6)
        assert np.allclose(ts.dimensions[:3], np.diag(edges[k]), rtol=1e-6)
        assert ts.time == pytest.approx(time[k])
    # The LAMMPS dump of a system, through MDAnalysis' LAMMPS dump reader.
    sim = small_system(granular)
    sim.write_lammps_dump(tmp_path / "state.lammpstrj", si=False)
    u = mda.Universe(str(tmp_path / "state.lammpstrj"), format="LAMMPSDUMP")
    x = sim.positions()
    assert len(u.atoms) == sim.size
    assert np.allclose(u.atoms.positions[np.argsort(u.atoms.ids)], x, rtol=1e-6, atol=1e-5)


def drop_key(text, table, key):
    """The scene text without key in [table]."""
    head = text.index("[%s]" % table)
    end = text.find("\n[", head + 1)
    end = len(text) if end < 0 else end
    body = re.sub(r"^%s\s*=.*\n" % re.escape(key), "", text[head:end], flags=re.M)
    return text[:head] + body + text[end:]


def scene_from(tmp_path, source, density=None, phi_end=0.6):
    """The quick isotropic compression scene started from a packing file."""
    text = open(os.path.join(REPO, "scenarios", "packings", "isotropic_compression.toml")).read()
    for key in ("count", "diameter_min", "diameter_max", "seed", "initial_speed", "density"):
        text = drop_key(text, "particles", key)
    text = drop_key(text, "compression", "phi_start")
    text = set_key(text, "particles", "from", '"%s"' % source)
    if density is not None:
        text = set_key(text, "particles", "density", density)
    for table, key, value in (("compression", "phi_end", phi_end),
                              ("compression", "volumetric_strain_rate", 5e-3),
                              ("compression", "relax_steps", 500),
                              ("output", "snapshot_every", 0)):
        text = set_key(text, table, key, value)
    path = tmp_path / "from.toml"
    path.write_text(text)
    return path


def test_compression_starts_from_a_lammps_data_file_or_an_h5md_frame(granular, tmp_path):
    # A LAMMPS data file: the run's first state is the file's packing.
    pack = granular.random_packing(150, 1.0, 3.0, density=2000.0, phi=0.3, seed=4)
    granular.write_lammps_data(pack, tmp_path / "start.data")
    granular.run_scene(scene_from(tmp_path, tmp_path / "start.data"), tmp_path / "a")
    phi0 = np.sum(4 / 3 * np.pi * pack.radius**3) / np.prod(pack.box_len)
    with h5py.File(tmp_path / "a" / "results.h5") as r:
        assert r["series/phi"][0] == pytest.approx(phi0, rel=1e-12)
        assert r["series/phi"][-1] == pytest.approx(0.6, rel=2e-3)
        assert np.allclose(np.sort(r["final_state/radius"][()]), np.sort(pack.radius),
                           rtol=1e-15)
    # The last frame of an H5MD series (a run of the shipped scene, shrunk).
    test_snapshot_series_h5md_holds_the_frames_with_box_and_units(granular, tmp_path)
    with h5py.File(tmp_path / "out" / "snapshots.h5md") as f:
        p = f["particles/all"]
        edges = p["box/edges/value"][-1]
        phi_last = np.sum(4 / 3 * np.pi * p["radius"][()]**3) / np.prod(np.diag(edges))
    granular.run_scene(scene_from(tmp_path, tmp_path / "out" / "snapshots.h5md", 2000.0, 0.65),
                       tmp_path / "b")
    with h5py.File(tmp_path / "b" / "results.h5") as r:
        assert r["series/phi"][0] == pytest.approx(phi_last, rel=1e-12)
    # A data file and a density together: the file's densities stand, the key is refused.
    with pytest.raises(granular.InputError, match="particles.density"):
        granular.run_scene(scene_from(tmp_path, tmp_path / "start.data", 2000.0),
                           tmp_path / "c", check_only=True)
