"""Systems that pickle, deep-copy and travel between processes with the same bits,
and the ASE round trip."""

import copy
import json
import multiprocessing
import pickle
import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hydrorattle as hr


def chain(n, rng):
    radii = rng.uniform(0.5, 1.2, n)
    pos = np.zeros((n, 3))
    for i in range(1, n):
        d = rng.normal(size=3)
        pos[i] = pos[i - 1] + d / np.linalg.norm(d) * (radii[i] + radii[i - 1]) * 1.1
    return pos, radii, [[i, i + 1] for i in range(n - 1)]


# (method, temperature) pairs the kernel takes.
CASES = [
    ("overdamped", None),
    ("overdamped", 0.3),
    ("overdamped2", None),
    ("rattle", None),
    ("rattle-stable", None),
    ("rattle-stable", 0.3),
    ("springs", 0.3),
]


def build(case, n, seed, precision):
    method, temperature = case
    rng = np.random.default_rng(seed)
    pos, radii, bonds = chain(n, rng)
    return hr.System(
        pos, radii, rng.uniform(1.0, 3.0, n), bonds=bonds, dt=0.01, method=method,
        temperature=temperature, seed=seed, precision=precision, allow_overlap=True,
    )


def same(a, b):
    assert a.state_bits() == b.state_bits()
    ta, tb = a.tensions, b.tensions
    assert (ta is None and tb is None) or np.array_equal(ta, tb)


@settings(max_examples=30, deadline=None)
@given(
    case=st.sampled_from(CASES),
    n=st.integers(1, 7),
    seed=st.integers(0, 2**63),
    before=st.integers(0, 5),
    after=st.integers(1, 5),
    precision=st.sampled_from(["f64", "f32"]),
)
def test_a_pickled_system_continues_with_the_same_bits(case, n, seed, before, after, precision):
    s = build(case, n, seed, precision)
    s.step(before)
    t = pickle.loads(pickle.dumps(s))
    same(s, t)
    assert t.precision == s.precision and t.dt == s.dt
    s.step(after)
    t.step(after)
    same(s, t)
    d = copy.deepcopy(s)
    s.step(2)
    d.step(2)
    same(s, d)


def _step_remotely(s, k):
    s.step(k)
    return s


def test_a_system_steps_in_another_process_with_the_same_bits():
    s = build(("rattle-stable", 0.3), 5, 7, "f64")
    s.step(3)
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(1) as pool:
        remote = pool.apply(_step_remotely, (s, 4))
    s.step(4)
    same(s, remote)


def test_a_corrupt_record_is_refused():
    with pytest.raises(ValueError, match="saved system"):
        hr._restore_system('{"version": 99}')


def test_ase_round_trip():
    ase = pytest.importorskip("ase")
    s = build(("rattle", None), 4, 3, "f64")
    s.step(5)
    atoms = s.to_atoms()
    assert isinstance(atoms, ase.Atoms)
    assert np.array_equal(atoms.arrays["radius"], s.radii)
    assert np.allclose(atoms.get_masses(), 4 / 3 * np.pi * s.radii**3 * s.densities)
    t = hr.System.from_atoms(atoms, dt=0.01, method="rattle", allow_overlap=True)
    assert np.array_equal(t.positions, s.positions)
    assert np.array_equal(t.bonds, s.bonds) and np.array_equal(t.lengths, s.lengths)
    assert t.time == s.time
    assert np.allclose(t.velocities, s.velocities, rtol=1e-12, atol=0)
    # Densities from the masses when the atoms carry none.
    del atoms.arrays["density"]
    u = hr.System.from_atoms(atoms, dt=0.01, method="rattle", allow_overlap=True)
    assert np.allclose(u.densities, s.densities, rtol=1e-12)
    with pytest.raises(ValueError, match="radii"):
        hr.System.from_atoms(ase.Atoms("X2", positions=[[0, 0, 0], [3, 0, 0]]), dt=0.1)


def saved(s):
    return json.loads(s._core.save_json())


def load(record):
    return hr._restore_system(json.dumps(record))


def test_a_damaged_record_is_refused_on_load_as_the_constructor_refuses_it():
    s = build(("rattle", None), 4, 3, "f64")
    s.step(2)
    good = saved(s)
    load(good)  # the record as saved loads

    def damaged(change):
        r = copy.deepcopy(good)
        change(r)
        return r

    nan = struct.unpack("<Q", struct.pack("<d", float("nan")))[0]
    zero = 0
    cases = {
        "NaN position": lambda r: r["pos"].__setitem__(0, nan),
        "radius 0": lambda r: r["radius"].__setitem__(1, zero),
        "dt 0": lambda r: r["params"].__setitem__("dt", zero),
        "coincident spheres": lambda r: r["pos"].__setitem__(slice(3, 6), r["pos"][0:3]),
        "short multipliers": lambda r: r.__setitem__("multipliers", r["multipliers"][:-1]),
        "unknown key": lambda r: r.__setitem__("colour", "red"),
        "unknown parameter": lambda r: r["params"].__setitem__("colour", "red"),
    }
    for name, change in cases.items():
        # A pickle whose record was damaged in transit: refused as it loads.
        data = pickle.dumps(Record(json.dumps(damaged(change))))
        with pytest.raises(ValueError, match="saved system") as e:
            pickle.loads(data)
        assert name and e.value


class Record:
    """A pickle of a system's record as System.__reduce__ writes one."""

    def __init__(self, text):
        self.text = text

    def __reduce__(self):
        return (hr._restore_system, (self.text,))


PINNED = """
[[particle]]
position = [0, 0, 0]
radius = 1.0
density = 2.0
fixed = true

[[particle]]
position = [0, 0, 2.5]
radius = 1.0
density = 2.0

[[particle]]
position = [2.5, 0, 2.5]
radius = 1.0
density = 2.0

[[bond]]
between = [1, 2]

[contact]
model = "hard"

[integrator]
method = "overdamped"
dt = 0.05
duration = 1.0
"""


def test_a_pinned_sphere_stays_pinned_through_a_pickle():
    s = hr.System.from_scene_text(PINNED)
    s.step(3)
    t = pickle.loads(pickle.dumps(s))
    same(s, t)
    s.step(10)
    t.step(10)
    same(s, t)
    # The pin held the first sphere where it was put.
    assert np.array_equal(t.positions[0], [0.0, 0.0, 0.0])


def test_ase_round_trip_carries_the_box():
    ase = pytest.importorskip("ase")
    box = (9.0, 10.0, 11.0)
    pos = np.array([[1.0, 1.0, 1.0], [4.0, 1.0, 1.0], [8.5, 9.0, 1.0]])
    s = hr.System(pos, 1.0, 2.0, dt=0.1, box=box)
    assert s.box == box
    atoms = s.to_atoms()
    assert tuple(atoms.pbc) == (True, True, True)
    assert np.array_equal(atoms.cell[:], np.diag(box))
    t = hr.System.from_atoms(atoms, dt=0.1)
    assert t.box == box
    s.step(3)
    t.step(3)
    assert s.state_bits() == t.state_bits()
    # Free space stays free space; a box on some axes only, or a skewed cell, is refused.
    free = hr.System(pos, 1.0, 2.0, dt=0.1)
    assert free.box is None and not any(free.to_atoms().pbc)
    assert hr.System.from_atoms(free.to_atoms(), dt=0.1).box is None
    atoms.pbc = (True, True, False)
    with pytest.raises(ValueError, match="some axes"):
        hr.System.from_atoms(atoms, dt=0.1)
    atoms.pbc = True
    atoms.cell[0, 1] = 1.0
    with pytest.raises(ValueError, match="diagonal"):
        hr.System.from_atoms(atoms, dt=0.1)


FAST_CLOUD = """
[cloud]
count = 40
cloud_radius = 9.0
seed = 3

[free_space]
method = "fast"
tolerance = 1e-5

[model]
rotation = true

[brownian]
temperature = 0.5

[integrator]
method = "overdamped"
dt = 0.05
duration = 1.0
"""

PSE_BOX = """
[suspension]
count = 24
fraction = 0.05
radius = 1.0
polydispersity = 0.2
density = 4.5
seed = 7

[box]
method = "pse"
tolerance = 1e-4

[brownian]
temperature = 0.5

[integrator]
method = "overdamped"
dt = 0.05
duration = 1.0
"""


@pytest.mark.parametrize("text", [FAST_CLOUD, PSE_BOX], ids=["fast", "pse"])
def test_a_pickled_system_keeps_its_fast_product(text):
    """A system on the fast free-space product (with rotation) or on PSE in a box
    pickles with its product and tolerance: the unpickled one takes the same next
    steps, bit for bit (on the dense path or the Ewald sum they differ)."""
    s = hr.System.from_scene_text(text)
    s.step(1)
    assert saved(s)["params"]["pse"] > 0
    t = pickle.loads(pickle.dumps(s))
    same(s, t)
    s.step(2)
    t.step(2)
    same(s, t)
    if "rotation" in text:
        assert np.abs(t.spins).max() > 0


@pytest.mark.parametrize("text", [FAST_CLOUD, PSE_BOX], ids=["fast", "pse"])
def test_a_fast_tolerance_out_of_range_is_refused_on_load(text):
    s = hr.System.from_scene_text(text)
    good = saved(s)
    load(good)
    for bad in [5.0, float("nan"), 0.0]:
        r = copy.deepcopy(good)
        r["params"]["pse"] = struct.unpack("<Q", struct.pack("<d", bad))[0]
        with pytest.raises(ValueError, match="saved system"):
            pickle.loads(pickle.dumps(Record(json.dumps(r))))
