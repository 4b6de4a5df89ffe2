"""Inputs refused where they are given, in words that name what is wrong: the box's
geometry (overlaps through a face, radii, far centres, huge edges), loads that overflow
on the way, bond indices past int64, parameters named."""

import numpy as np
import pytest

import hydrorattle as hr

BOX = (10.0, 10.0, 10.0)


def test_spheres_overlapping_through_a_face_are_refused_at_construction():
    # 0.5 and 9.7 are 0.8 apart through the face x = 0 (the minimum image).
    pos = [[0.5, 5.0, 5.0], [9.7, 5.0, 5.0]]
    with pytest.raises(ValueError, match="overlap") as e:
        hr.System(pos, 1.0, 2.0, dt=0.1, box=BOX)
    assert e.value.index == (0, 1) and e.value.kind == "particle_overlap"
    # In free space they are 9.2 apart; with overlaps allowed the box takes them.
    hr.System(pos, 1.0, 2.0, dt=0.1)
    hr.System(pos, 1.0, 2.0, dt=0.1, box=BOX, allow_overlap=True).step(1)


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_a_radius_not_below_half_the_box_says_so(precision):
    pos = [[1.0, 1.0, 1.0], [6.0, 6.0, 6.0]]
    for call in (
        lambda: hr.System(pos, [1.0, 5.0], 2.0, dt=0.1, box=BOX, precision=precision),
        lambda: hr.mobility(pos, [1.0, 5.0], box=BOX, precision=precision),
        lambda: hr.mobility_dot(pos, [1.0, 5.0], np.ones((2, 3)), box=BOX, precision=precision),
    ):
        with pytest.raises(ValueError, match="not below half the box's smallest edge") as e:
            call()
        assert e.value.index == 1


def test_a_box_too_large_for_its_volume_says_so():
    big = (1e300, 1e300, 1e300)
    for call in (
        lambda: hr.System([[0.0, 0, 0]], 1.0, 2.0, dt=0.1, box=big),
        lambda: hr.mobility([[0.0, 0, 0]], 1.0, box=big),
        lambda: hr.System([[0.0, 0, 0]], 1.0, 2.0, dt=0.1, box=(1e13,) * 3, precision="f32"),
    ):
        with pytest.raises(ValueError, match="volume overflows"):
            call()


def test_centres_too_far_from_the_box_say_so():
    pos = [[1e300, 0.0, 0.0], [3.0, 0.0, 0.0]]
    for call in (
        lambda: hr.System(pos, 1.0, 2.0, dt=0.1, box=BOX),
        lambda: hr.mobility(pos, 1.0, box=BOX),
    ):
        with pytest.raises(ValueError, match="box edges") as e:
            call()
        assert e.value.index == 0
    # In f32 the reach is 1/sqrt(eps) = 2896 edges.
    far = [[3e4 * 10, 0.0, 0.0], [3.0, 0.0, 0.0]]
    hr.System(far, 1.0, 2.0, dt=0.1, box=BOX)
    with pytest.raises(ValueError, match="box edges"):
        hr.System(far, 1.0, 2.0, dt=0.1, box=BOX, precision="f32")


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_loads_that_overflow_on_the_way_are_scaled(precision):
    rng = np.random.default_rng(2)
    pos = rng.uniform(0, 10, (5, 3))
    f = rng.uniform(-1.0, 1.0, (5, 3))
    unit = hr.mobility_dot(pos, 0.3, f, box=BOX, method="ewald")
    huge = hr.mobility_dot(pos, 0.3, f * 1e308, box=BOX, method="ewald")
    assert np.isfinite(huge).all()
    # Linear: the product of the scaled loads is the product of the loads, scaled.
    assert np.allclose(huge / 1e308, unit, rtol=1e-12, atol=0)
    if precision == "f32":
        with pytest.raises(OverflowError, match="float32"):
            hr.mobility_dot(pos, 0.3, f * 1e308, box=BOX, precision="f32")
    # With torques too (rotation: the packed grand mobility).
    u, w = hr.mobility_dot(pos, 0.3, f * 1e300, torques=f * 1e300, box=BOX)
    u1, w1 = hr.mobility_dot(pos, 0.3, f, torques=f, box=BOX)
    assert np.allclose(u / 1e300, u1, rtol=1e-12) and np.allclose(w / 1e300, w1, rtol=1e-12)


def test_a_bond_index_past_int64_is_named_as_given():
    pos = [[0.0, 0, 0], [3.0, 0, 0]]
    bonds = np.array([[0, 2**64 - 1]], dtype=np.uint64)
    with pytest.raises(ValueError, match="18446744073709551615"):
        hr.System(pos, 1.0, 2.0, bonds=bonds, dt=0.1)


def test_a_refused_bond_names_its_index():
    pos = [[0.0, 0, 0], [3.0, 0, 0], [6.0, 0, 0]]
    with pytest.raises(ValueError) as e:
        hr.System(pos, 1.0, 2.0, bonds=[[0, 1], [1, 1]], dt=0.1)
    assert e.value.index == 1


def test_set_state_names_time():
    s = hr.System([[0.0, 0, 0]], 1.0, 2.0, dt=0.1)
    with pytest.raises(TypeError) as e:
        s.set_state(time="x")
    assert str(e.value).startswith("time must be a real number"), str(e.value)
