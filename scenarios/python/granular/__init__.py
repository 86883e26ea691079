"""granular: DEM of granular packings from Python (docs/python.md).

Compose a protocol from the stages the engine's scene drivers are made of, on the same
compiled engine (OpenMP threads; the GIL is released while it steps):

    import granular
    pack = granular.random_packing(500, 0.9, 1.1, density=2500, phi=0.3, seed=1)
    sim = granular.System(pack, contact={"normal": "hertz", "shear_modulus": 29e3,
                                         "poisson": 0.2, "tangential": "coulomb",
                                         "tangential_law": "mindlin", "friction": 0.3},
                          dt=5e-3, skin=0.1)
    sim.servo_to_pressure(0.1)
    print(sim.probe_moduli(1e-5, 2000, 2000))

Units are the engine's: lengths in mm, times in us, masses in ug, so densities in ug/mm^3
(numerically kg/m^3: glass is 2500), forces in N, stresses and moduli in MPa, energies in mJ. Particle arrays are in identity order (the order the particles were
created in). Scene files run unchanged through `run_scene`, with the same results as the
command line.
"""

import atexit as _atexit
import os as _os

from . import _granular
from ._granular import InputError, Packing, PhysicsError, SavedState  # noqa: F401

__all__ = [
    "InputError", "PhysicsError", "Packing", "SavedState", "System", "initialize", "threads",
    "random_packing", "read_lammps_data", "write_lammps_data", "read_state",
    "read_saved_state", "run_scene",
    "scenes", "toml_text",
]

MEASURE_KEYS = (
    "pressure", "stress", "stress_normal", "stress_tangential", "phi", "z", "z_corrected",
    "rattlers", "contacts", "ekin", "ekin_rot", "epot", "fabric", "contact_histogram", "chi",
    "max_overlap", "volume", "particles")


def initialize(threads=None):
    """Start the engine with `threads` host threads (default: $GRANULAR_THREADS, then
    OMP_NUM_THREADS or all cores). Call before the first System; later calls do nothing."""
    if threads is None:
        threads = int(_os.environ.get("GRANULAR_THREADS", "0") or 0)
    _granular.initialize(int(threads))


def threads():
    """The number of host threads the engine runs on."""
    initialize()
    return _granular.threads()


def _finalize():
    import gc
    gc.collect()
    _granular.finalize()  # only when no simulation is left alive


_atexit.register(_finalize)


def random_packing(count, diameter_min, diameter_max, density, phi, seed=1, speed=0.0):
    """A random non-overlapping gas of `count` spheres with diameters uniform in
    [diameter_min, diameter_max] (mm) at volume fraction `phi` (<= 0.45) in a periodic cube.
    Every particle's randomness derives from (seed, index)."""
    initialize()
    return _granular.random_packing(int(count), float(diameter_min), float(diameter_max),
                                    float(density), float(phi), int(seed), float(speed))


def read_lammps_data(path):
    """A LAMMPS data file of atom style sphere (SI units, converted to mm, us, ug)."""
    return _granular.read_lammps_packing(str(path))


def read_state(path, group="/final_state"):
    """A particle state group the engine wrote (results.h5's /final_state, a snapshot)."""
    return _granular.read_state_packing(str(path), group)


def write_lammps_data(packing, path):
    """A LAMMPS data file (atom style sphere, SI units, atom type = species + 1, ids 1..n)
    that LAMMPS' read_data and read_lammps_data read back."""
    with open(path, "w") as f:
        f.write(_granular.lammps_data_text(packing))


def read_saved_state(path):
    """A complete saved state (System.save(...).write(path)): particles and contact history."""
    return SavedState.read(str(path))


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        x = float(v)
        if x != x:
            return "nan"
        if x in (float("inf"), float("-inf")):
            return "inf" if x > 0 else "-inf"
        return repr(v) if isinstance(v, int) else repr(x)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError("cannot write %r as a TOML value" % (v,))


def toml_text(tables):
    """TOML text of nested dicts: {"contact": {...}, "materials": {"glass": {...}}}."""
    lines = []

    def table(name, d):
        scalars = [(k, v) for k, v in d.items() if not isinstance(v, dict)]
        subs = [(k, v) for k, v in d.items() if isinstance(v, dict)]
        if scalars or not subs:
            lines.append("[%s]" % name)
            lines.extend("%s = %s" % (k, _toml_value(v)) for k, v in scalars)
        for k, v in subs:
            table(name + "." + k, v)

    for name, d in tables.items():
        table(name, d)
    return "\n".join(lines) + "\n"


class System:
    """A DEM simulation of a packing in a periodic box (with optional walls).

    contact:   the [contact] table of a scene file as a dict (docs/contact_laws.md), e.g.
               {"normal": "linear", "kn": 1e3, "gamma_n": 0.5, "tangential": "coulomb",
               "kt": 800, "friction": 0.5}; with `materials`, the contact options of the
               materials' Hertz law ({"tangential": "mindlin", "damping": ...}).
    materials: {"glass": {"young_modulus": 63e3, "poisson": 0.23, "density": 2500,
               "friction": 0.3, "restitution": 0.9}, ...}; species index the materials in
               name order; a material's density replaces its particles'.
    dt, skin:  time step (us) and neighbour-list skin (mm). A time step too large for the
               stiffest contact is refused, saying which value to lower.
    damping, rotational_damping: background damping rates (1/us).
    precision: "double" (default) or "mixed": the force pass reads the positions as 32-bit
               fixed-point fractions of the box, forces stay in double (docs/mixed_precision.md;
               classical contact laws only).
    Keys are checked as in a scene file: a misspelt one is refused, named.
    """

    def __init__(self, packing, contact=None, materials=None, dt=None, skin=None,
                 damping=0.0, rotational_damping=0.0, rattler_threshold=3, max_overlap=0.3,
                 gravity=(0.0, 0.0, 0.0), precision="double", _sim=None):
        if _sim is not None:
            self._sim = _sim
            return
        self._sim = _simulation(_granular.make_simulation, packing, contact, materials, dt, skin,
                                damping, rotational_damping, rattler_threshold, max_overlap,
                                gravity, precision)

    # --- stepping ------------------------------------------------------------------------
    def step(self, n=1):
        """Advance n steps (the GIL is released meanwhile)."""
        self._sim.step(int(n))

    def run(self, steps, every=None, callback=None, check=True):
        """Advance `steps` steps; every `every` steps (default: all at once) call
        callback(system) and, with check, stop a run that went wrong (NaN, runaway overlap)
        with a PhysicsError. A callback returning False ends the run early."""
        steps = int(steps)
        every = int(every or steps or 1)
        done = 0
        while done < steps:
            n = min(every, steps - done)
            self._sim.step(n)
            done += n
            if check:
                self._sim.check_health()
            if callback is not None and callback(self) is False:
                break
        return done

    @property
    def strain_rate(self):
        """True strain rates of the box edges per axis (1/us; negative compresses)."""
        return tuple(self._sim.strain_rate)

    @strain_rate.setter
    def strain_rate(self, rates):
        if isinstance(rates, (int, float)):
            rates = (rates, rates, rates)
        self._sim.strain_rate = tuple(float(r) for r in rates)

    time = property(lambda self: self._sim.time, doc="simulated time (us)")
    steps = property(lambda self: self._sim.steps, doc="steps taken")
    size = property(lambda self: self._sim.size, doc="number of particles")
    dt = property(lambda self: self._sim.dt, doc="time step (us)")
    model = property(lambda self: self._sim.model, doc="the contact law")
    mass = property(lambda self: self._sim.mass, doc="total particle mass (ug)")
    box_len = property(lambda self: tuple(self._sim.box_len), doc="box edges (mm)")
    box_lo = property(lambda self: tuple(self._sim.box_lo), doc="box corner (mm)")

    # --- measures --------------------------------------------------------------------------
    def measure(self):
        """Stress tensor (xx yy zz xy xz yz, MPa, positive in compression) and its normal and
        tangential parts, pressure, volume fraction, Z (z: 2 contacts / N; z_corrected:
        without rattlers), rattlers, energies (mJ), fabric, contact-number histogram."""
        return self._sim.measure()

    def packing(self):
        """A copy of the particles (positions wrapped into the box) and the box."""
        return self._sim.packing()

    def positions(self):
        return self._sim.packing().positions

    def velocities(self):
        return self._sim.packing().velocities

    def forces(self):
        """Force on each particle at the last step (N), shape (n, 3)."""
        return self._sim.forces()

    def contacts(self):
        """The contact network: arrays i, j (identities, i < j), branch (from i to j, mm),
        normal_force (N, positive repulsive), tangential_force (on i, N), overlap (mm)."""
        return self._sim.contacts()

    def write_lammps_dump(self, path, si=True, append=False):
        """The particles as a LAMMPS dump frame (ITEM headers; columns id type radius x y z
        vx vy vz omegax omegay omegaz fx fy fz; SI units unless si=False), which LAMMPS'
        read_dump, OVITO and MDAnalysis read. append adds a frame to the file."""
        with open(path, "a" if append else "w") as f:
            f.write(self._sim.lammps_dump_text(bool(si)))

    # --- walls -----------------------------------------------------------------------------
    def set_walls(self, walls):
        """Planar walls: dicts with name, normal (outward: pointing away from the particles),
        point (mm: where the plane is now), velocity (mm/us, any direction: a wall moving
        along its plane shears the particles touching it), material (species slot). The box
        axis a wall closes must not be periodic (Packing.periodic). Replaces all walls."""
        specs = []
        t = self.time
        for w in walls:
            w = dict(w)
            v = [float(x) for x in w.get("velocity", (0.0, 0.0, 0.0))]
            p = [float(x) for x in w.get("point", (0.0, 0.0, 0.0))]
            w["point"] = tuple(p[k] - v[k] * t for k in range(3))  # the engine's: at t = 0
            specs.append(w)
        self._sim.set_walls(specs)

    def wall_loads(self):
        """Per wall: force and torque on it (N, N mm), contacts, energy, max_overlap."""
        return self._sim.wall_loads()

    # --- stages ----------------------------------------------------------------------------
    def strain_to_phi(self, phi, rate, every=500):
        """Strain the box isotropically at `rate` per axis (negative compresses) until the
        volume fraction crosses phi; returns the steps taken."""
        return self._sim.strain_to_phi(float(phi), float(rate), int(every))

    def relax(self, ratio=1e-8, max_steps=100000, every=500):
        """Relax at fixed box until E_kin/E_pot < ratio (or max_steps); returns the ratio."""
        return self._sim.relax(float(ratio), int(max_steps), int(every))

    def servo_to_pressure(self, pressure, tolerance=0.02, ekin_ratio=1e-6, max_cycles=2000):
        """Drive the packing to an isotropic `pressure` (MPa) by straining the box (the
        scenes' Hertz-law servo); returns converged, cycles, steps and the measurements."""
        return self._sim.servo_to_pressure(float(pressure), float(tolerance), float(ekin_ratio),
                                           int(max_cycles))

    def probe_moduli(self, amplitude, strain_steps, relax_steps, restarting=True,
                     orientations=1):
        """Bulk K, shear G and P-wave M moduli (MPa) from small strains of `amplitude`.
        restarting: each mode from a copy of this state, against a reference run without
        strain (the state is left as it is); otherwise in place, each mode reversed."""
        return self._sim.probe_moduli(float(amplitude), int(strain_steps), int(relax_steps),
                                      bool(restarting), int(orientations))

    # --- saved states ----------------------------------------------------------------------
    def save(self, path=None):
        """The complete state (particles, box, every contact's history); written to path
        (HDF5) when given."""
        state = self._sim.save()
        if path is not None:
            state.write(str(path))
        return state

    def restart(self, state):
        """A new System from a saved state under this system's contact law and settings."""
        return System(None, _sim=self._sim.restart(state))

    @classmethod
    def from_saved(cls, state, contact=None, materials=None, dt=None, skin=None, damping=0.0,
                   rotational_damping=0.0, rattler_threshold=3, max_overlap=0.3,
                   gravity=(0.0, 0.0, 0.0), precision="double"):
        """A System continuing a saved state (SavedState or a path) under a contact law, with
        the settings of System()."""
        if not isinstance(state, SavedState):
            state = read_saved_state(state)
        return cls(None, _sim=_simulation(_granular.restore_simulation, state, contact,
                                          materials, dt, skin, damping, rotational_damping,
                                          rattler_threshold, max_overlap, gravity, precision))


def _simulation(factory, start, contact, materials, dt, skin, damping, rotational_damping,
                rattler_threshold, max_overlap, gravity, precision="double"):
    """The compiled simulation of a packing or a saved state (factory: make_simulation or
    restore_simulation) under the contact law of `contact` and `materials`."""
    if dt is None or skin is None:
        raise InputError("a System needs dt (us) and skin (mm)")
    tables = {}
    if materials:
        tables["materials"] = dict(materials)
    if contact:
        tables["contact"] = dict(contact)
    if not tables:
        raise InputError("a System needs contact={...} or materials={...}")
    initialize()
    return factory(start, toml_text(tables), "<System contact>", float(dt), float(skin),
                   float(damping), float(rotational_damping), int(rattler_threshold),
                   float(max_overlap), tuple(float(g) for g in gravity), str(precision))


def scenes():
    """The shipped scene drivers: name -> description."""
    return _granular.scenes()


def run_scene(path, out_dir, charts=False, progress=False, check_only=False):
    """Run a scene file as `granular run` does (same drivers, same results for the same
    thread count); outputs go to out_dir. check_only reads and checks every key only."""
    initialize()
    _granular.run_scene(str(path), str(out_dir), bool(charts), bool(progress), bool(check_only))
