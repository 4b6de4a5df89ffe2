"""Inputs that never pass silently: each works as meant or raises a
ValueError / TypeError naming the parameter; what the first step would refuse is
refused when the system is built; the kernel's kinds and messages reach Python."""

import numpy as np
import pytest

import hydrorattle as hr

POS = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]]


def test_fractional_bond_indices_are_refused():
    with pytest.raises(ValueError, match=r"bonds\[0, 1\]: particle index 1.5 is not an integer"):
        hr.System(POS, 1.0, 1.0, bonds=[[0, 1.5]], dt=0.1)
    # Whole floats are the indices they name.
    s = hr.System(POS, 1.0, 1.0, bonds=[[0.0, 1.0]], dt=0.1)
    assert s.bonds.tolist() == [[0, 1]]
    with pytest.raises(TypeError, match="bonds"):
        hr.System(POS, 1.0, 1.0, bonds=[["a", "b"]], dt=0.1)


@pytest.mark.parametrize("precision,tiny", [("f64", 1e-310), ("f32", 1e-39)])
def test_subnormal_radii_are_refused(precision, tiny):
    for call in (
        lambda: hr.mobility(POS, [tiny, 1.0], precision=precision),
        lambda: hr.mobility_dot(POS, [tiny, 1.0], np.ones((2, 3)), precision=precision),
        lambda: hr.System(POS, [tiny, 1.0], 1.0, dt=0.1, precision=precision),
    ):
        with pytest.raises(ValueError, match="particle 0: radius must be > 0 and normal") as e:
            call()
        assert e.value.index == 0 and e.value.kind == "particle_bad_radius"
    # The smallest normal radius gives a finite mobility.
    m = hr.mobility([[0, 0, 0]], [np.finfo(precision.replace("f", "float")).tiny], precision=precision)
    assert np.isfinite(m).all()


def test_complex_input_is_a_type_error():
    z = np.array(POS, dtype=complex)
    with pytest.raises(TypeError, match="positions must hold real numbers"):
        hr.System(z, 1.0, 1.0, dt=0.1)
    with pytest.raises(TypeError, match="positions"):
        hr.mobility(z, 1.0)
    with pytest.raises(TypeError, match="radii"):
        hr.mobility(POS, [1.0 + 1j, 1.0])
    with pytest.raises(TypeError, match="forces"):
        hr.mobility_dot(POS, 1.0, np.ones((2, 3)) * 1j)
    with pytest.raises(TypeError, match="dt must be a real number, not a complex"):
        hr.System(POS, 1.0, 1.0, dt=0.1 + 0j)
    s = hr.System(POS, 1.0, 1.0, dt=0.1)
    with pytest.raises(TypeError, match="velocities"):
        s.set_state(velocities=np.zeros((2, 3), dtype=complex))


def test_flags_take_bools_and_0_or_1():
    a = hr.System(POS, 1.0, 1.0, dt=0.1, rotation=1, method="overdamped")
    b = hr.System(POS, 1.0, 1.0, dt=0.1, rotation=True, method="overdamped")
    a.step(2), b.step(2)
    assert a.state_bits() == b.state_bits()
    for bad in (2, 0.5, "yes"):
        with pytest.raises(TypeError, match="rotation must be True or False"):
            hr.System(POS, 1.0, 1.0, dt=0.1, rotation=bad)


@pytest.mark.parametrize(
    "kw,error,match",
    [
        ({"dt": 0.0}, ValueError, "time step must be finite and > 0"),
        ({"dt": float("nan")}, ValueError, "time step"),
        ({"dt": 0.1, "seed": -1}, ValueError, "seed must be an integer"),
        ({"dt": 0.1, "seed": 2**64}, ValueError, "seed"),
        ({"dt": 0.1, "seed": 1.5}, TypeError, "seed must be an integer"),
        ({"dt": 0.1, "viscosity": -1.0}, ValueError, "viscosity"),
        ({"dt": 0.1, "tolerance": 0.0}, ValueError, "tolerance"),
        ({"dt": 0.1, "max_iterations": -3}, ValueError, "max_iterations"),
        ({"dt": 0.1, "gravity": [0, 0]}, TypeError, "gravity must be three real numbers"),
        ({"dt": 0.1, "method": "rattle", "temperature": 1.0}, ValueError, "not supported"),
        ({"dt": 0.1, "box": (10, 10, 10), "wall": -5.0}, ValueError, "periodic box with a wall"),
        ({"dt": 0.1, "box": (10, -1, 10)}, ValueError, "box"),
    ],
)
def test_parameter_errors_are_raised_when_the_system_is_built(kw, error, match):
    with pytest.raises(error, match=match):
        hr.System(POS, 1.0, 1.0, **kw)


def test_kinds_come_from_the_kernel():
    with pytest.raises(ValueError) as e:
        hr.System(POS, 1.0, 1.0, dt=0.0)
    assert e.value.kind == "bad_time_step"
    with pytest.raises(ValueError) as e:
        hr.System(POS, 1.0, 1.0, dt=0.1, method="rattle", temperature=1.0)
    assert e.value.kind == "unsupported"


def test_overlap_at_the_start_is_refused_unless_allowed():
    close = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]]
    with pytest.raises(ValueError, match="particles 0 and 1 overlap") as e:
        hr.System(close, 1.0, 1.0, dt=0.1)
    assert e.value.index == (0, 1)
    hr.System(close, 1.0, 1.0, dt=0.1, allow_overlap=True).step(1)


def test_coincident_centres_say_so_even_where_overlap_is_allowed():
    same = [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]
    for kw in ({}, {"allow_overlap": True}):
        with pytest.raises(ValueError, match="particles 0 and 1: coincident centres") as e:
            hr.System(same, 1.0, 1.0, dt=0.1, **kw)
        assert e.value.kind == "particle_coincident" and e.value.index == (0, 1)
    with pytest.raises(ValueError, match="coincident centres"):
        hr.mobility(same, [1.0, 1.0])


def test_negative_time_works_as_a_clock_offset():
    s = hr.System(POS, 1.0, 1.0, dt=0.25)
    s.set_state(time=-5)
    s.step(4)
    assert s.time == -4.0
    frames = list(s.run(until=-3.0))
    assert frames[-1].time == pytest.approx(-3.0)
    with pytest.raises(ValueError, match="time must be finite"):
        s.set_state(time=float("inf"))


@pytest.mark.parametrize("method", ["overdamped", "overdamped2", "rattle", "rattle-stable", "springs"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_force_is_reported_as_such(method, bad):
    s = hr.System(POS, 1.0, 1.0, bonds=[[0, 1]], dt=0.01, method=method)
    before = s.state_bits()

    def force(p):
        f = np.zeros_like(p)
        f[1, 2] = bad
        return f

    with pytest.raises(hr.NonFiniteError, match="particle 1: the force on it is NaN or infinite") as e:
        s.step(1, force=force)
    assert e.value.kind == "non_finite_force" and e.value.index == 1
    assert s.state_bits() == before


def test_step_n_keeps_the_completed_steps_and_says_how_many():
    # A heavy big sphere falls onto a light small one: an overlap after a few steps,
    # with the GIL released (no force callable).
    s = hr.System([[0, 0, 0], [0, 0, 6.0]], [1.0, 2.0], [1.0, 5.0], dt=0.1)
    with pytest.raises(hr.OverlapError) as e:
        s.step(1000)
    done = e.value.completed
    assert 0 < done < 1000
    assert s.time == pytest.approx(done * 0.1)
    # With a force callable: it fails on its fourth call.
    s = hr.System(POS, 1.0, 1.0, dt=0.1)
    calls = []

    def force(p):
        calls.append(1)
        if len(calls) == 4:
            raise RuntimeError("enough")
        return np.zeros_like(p)

    with pytest.raises(RuntimeError, match="enough") as e2:
        s.step(10, force=force)
    assert e2.value.completed == 3 and s.time == pytest.approx(0.3)
