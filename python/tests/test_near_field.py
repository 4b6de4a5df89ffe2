"""mobility(..., near_field=True) against exact two-sphere and sphere-wall values."""

import math

import numpy as np
import pytest

import hydrorattle as hr

U0 = 1.0 / (6.0 * math.pi)  # Stokes' mobility of the unit sphere, eta = 1


def bispherical_sum(alpha, wall):
    """Stimson and Jeffery's (two spheres) or Brenner's (the wall) series, 1 / lambda."""
    total = 0.0
    for n in range(1, 5000):
        k = 2 * n + 1
        a = 2 * math.sinh(k * alpha) + k * math.sinh(2 * alpha)
        b = 4 * math.sinh(k * alpha / 2) ** 2 - k * k * math.sinh(alpha) ** 2
        c = n * (n + 1) / ((2 * n - 1) * (2 * n + 3))
        t = c * (a / b - 1) if wall else c * (1 - b / a)
        total += t
        if abs(t) < 1e-16 * abs(total):
            break
    return 1.0 / (4.0 / 3.0 * math.sinh(alpha) * total)


@pytest.mark.parametrize("s", [2.01, 2.05, 2.1, 2.5, 3.0, 4.0])
def test_two_spheres_fall_as_stimson_and_jeffery_say(s):
    m = hr.mobility([[0, 0, 0], [0, 0, s]], [1.0, 1.0], near_field=True)
    u = (m[2, 2] + m[2, 5]) / U0
    exact = bispherical_sum(math.acosh(s / 2), wall=False)
    assert abs(u / exact - 1) < 5e-3, (u, exact)
    # RPY alone is off by up to 4.6 % here.
    rpy = hr.mobility([[0, 0, 0], [0, 0, s]], [1.0, 1.0])
    assert m.shape == rpy.shape == (6, 6)


def test_side_by_side_and_spin_at_2_1():
    m = hr.mobility([[0, 0, 0], [0, 0, 2.1]], [1.0, 1.0], rotation=True, near_field=True)
    assert m.shape == (12, 12)
    u = (m[0, 0] + m[0, 3]) / U0
    spin = (m[7, 0] + m[7, 3]) / U0
    assert abs(u / 1.3917 - 1) < 5e-3, u
    assert abs(abs(spin) / 0.137 - 1) < 0.02, spin
    # Without rotation: the translational block of the same inverse.
    t = hr.mobility([[0, 0, 0], [0, 0, 2.1]], [1.0, 1.0], near_field=True)
    np.testing.assert_allclose(t, m[:6, :6], rtol=1e-12)


@pytest.mark.parametrize("h", [1.01, 1.1, 1.5, 2.0, 4.0, 10.0])
def test_sphere_approaches_the_wall_as_brenner_says(h):
    m = hr.mobility([[0, 0, h]], [1.0], wall=0.0, near_field=True)
    exact = bispherical_sum(math.acosh(h), wall=True)
    assert abs(m[2, 2] / U0 / exact - 1) < 5e-3, (m[2, 2] / U0, exact)


def test_beyond_the_cutoff_it_is_rpy():
    pos = [[0, 0, 0], [7, 0, 0], [0, 8, 0]]
    for rotation in (False, True):
        a = hr.mobility(pos, 1.0, rotation=rotation, near_field=True)
        b = hr.mobility(pos, 1.0, rotation=rotation)
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_positive_definite_with_overlaps(precision):
    rng = np.random.default_rng(5)
    for _ in range(20):
        n = 6
        pos = rng.uniform(0, 4, (n, 3))
        radii = rng.uniform(0.7, 1.5, n)
        d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
        np.fill_diagonal(d, np.inf)
        if (d <= np.abs(radii[:, None] - radii[None]) * 1.01).any():
            continue
        m = hr.mobility(pos, radii, rotation=True, precision=precision, near_field=True)
        assert m.dtype == np.dtype(np.float32 if precision == "f32" else np.float64)
        m = m.astype(np.float64)
        np.testing.assert_allclose(m, m.T, rtol=1e-4, atol=1e-7)
        assert np.linalg.eigvalsh((m + m.T) / 2).min() > 0


def test_in_a_large_box_a_close_pair_is_free_space_plus_hasimoto():
    # Each translation block shifts by -2.837297 a / L U0 (Hasimoto); together the
    # pair's velocity by twice that, apart (opposite forces) by O((a/L)^3) only.
    pos = [[50, 50, 50], [52.1, 50, 50]]
    free = hr.mobility(pos, 1.0, near_field=True)
    boxed = hr.mobility(pos, 1.0, box=(100, 100, 100), near_field=True)
    shift = 2.837297 / 100 * U0
    for k in range(3):
        together = (boxed[k, k] + boxed[k, 3 + k]) - (free[k, k] + free[k, 3 + k])
        apart = (boxed[k, k] - boxed[k, 3 + k]) - (free[k, k] - free[k, 3 + k])
        assert abs(together / (-2 * shift) - 1) < 0.1, together
        assert abs(apart) < 1e-3 * shift, apart


def test_in_the_box_a_pair_across_a_face_is_the_pair_inside():
    across = np.array([[11.0, 3, 4], [1.05, 3, 4.2], [5, 7, 2]])
    inside = across + [6.0, 1, 2]
    inside[:, 0] %= 12
    a = [1.0, 1.0, 1.5]
    x = hr.mobility(across, a, rotation=True, box=(12, 12, 12), near_field=True)
    y = hr.mobility(inside, a, rotation=True, box=(12, 12, 12), near_field=True)
    np.testing.assert_allclose(x, y, rtol=0, atol=1e-9 * np.abs(x).max())
    assert np.linalg.eigvalsh((x + x.T) / 2).min() > 0


def test_box_with_wall_and_other_levels_are_refused():
    with pytest.raises(ValueError, match="a wall or a box"):
        hr.mobility([[1, 1, 1], [3, 1, 1]], 1.0, wall=0.0, box=(10, 10, 10), near_field=True)
    with pytest.raises(ValueError, match="rpy"):
        hr.mobility([[1, 1, 1], [3, 1, 1]], 1.0, hydro="oseen", near_field=True)
    with pytest.raises(ValueError, match="size ratio"):
        hr.mobility([[0, 0, 0], [0, 0, 13]], [1.0, 11.0], near_field=True)


RHO1 = 3.0 / (4.0 * math.pi)  # unit buoyant weight of the unit sphere, g = 1


@pytest.mark.parametrize("method", ["overdamped", "overdamped2"])
def test_system_steps_with_the_near_field(method):
    # Two spheres at s = 2.1 fall along their line of centres at Stimson and Jeffery's
    # speed; without the near field RPY is 4.6 % fast.
    pos = [[0, 0, -1.05], [0, 0, 1.05]]
    exact = bispherical_sum(math.acosh(1.05), wall=False) * U0
    for near, close in [(True, True), ({"cutoff": 4.0, "min_gap": 1e-3}, True), (False, False)]:
        s = hr.System(pos, 1.0, RHO1, dt=0.01, method=method, near_field=near)
        s.step()
        u = -s.velocities[:, 2]
        assert (abs(u / exact - 1) < 5e-3).all() == close, (near, u, exact)


def test_system_near_field_above_the_wall_and_refusals():
    s = hr.System([[0, 0, 1.1]], 1.0, RHO1, dt=0.1, wall=0.0, near_field=True)
    s.step()
    exact = bispherical_sum(math.acosh(1.1), wall=True) * U0
    assert abs(-s.velocities[0, 2] / exact - 1) < 5e-3
    with pytest.raises(ValueError):
        hr.System([[0, 0, 0], [0, 0, 2.5]], 1.0, RHO1, dt=0.1, method="rattle", near_field=True)
    with pytest.raises(TypeError):
        hr.System([[0, 0, 0], [0, 0, 2.5]], 1.0, RHO1, dt=0.1, near_field={"cutof": 1.0})
