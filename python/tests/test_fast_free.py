"""`mobility_dot(..., method="fast")` in free space: the kernel's fast free-space RPY
product against the exact pair sum (``method="dense"``, itself checked against pygrpy
in test_mobility.py) within the requested tolerance, on random polydisperse clouds
with overlapping pairs, with rotation too; the same bits on a rerun; what it cannot serve refused with a
ValueError saying why."""

import numpy as np
import pytest

import hydrorattle as hr


def cloud(rng, n, radius):
    """`n` spheres of radii 0.5 to 1.2 uniform in a ball of radius `radius`, every
    fifth overlapping an earlier one, none inside another."""
    radii = rng.uniform(0.5, 1.2, n)
    pos = np.empty((n, 3))
    k = 0
    while k < n:
        if k > 0 and k % 5 == 0:
            j = rng.integers(k)
            d = rng.normal(size=3)
            d *= (abs(radii[j] - radii[k]) + 0.3 + rng.uniform(0, 0.5)) / np.linalg.norm(d)
            pos[k] = pos[j] + d
        else:
            x = rng.uniform(-1, 1, 3)
            if x @ x > 1:
                continue
            pos[k] = radius * x
        dist = np.linalg.norm(pos[:k] - pos[k], axis=1)
        if not np.any(dist < np.abs(radii[:k] - radii[k]) + 0.05):
            k += 1
    return pos, radii


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


@pytest.mark.parametrize("tolerance", [1e-3, 1e-5, 1e-8])
def test_fast_within_tolerance_of_dense(tolerance):
    rng = np.random.default_rng(int(-np.log10(tolerance)))
    pos, radii = cloud(rng, 400, 12.0)
    f = rng.normal(size=(400, 3))
    exact = hr.mobility_dot(pos, radii, f, method="dense")
    fast = hr.mobility_dot(pos, radii, f, method="fast", tolerance=tolerance)
    assert fast.shape == (400, 3)
    err = rel(fast, exact)
    assert err < tolerance, err
    # The fast product itself, not the pair sum: its own error is there.
    assert err > 1e-4 * tolerance, err
    again = hr.mobility_dot(pos, radii, f, method="fast", tolerance=tolerance)
    assert np.array_equal(again, fast)


def test_fast_in_f32_and_by_default_tolerance():
    rng = np.random.default_rng(7)
    pos, radii = cloud(rng, 200, 9.0)
    f = rng.normal(size=(200, 3))
    exact = hr.mobility_dot(pos, radii, f)
    default = hr.mobility_dot(pos, radii, f, method="fast")
    assert rel(default, exact) < 1e-4
    single = hr.mobility_dot(pos, radii, f, method="fast", tolerance=1e-4, precision="f32")
    assert single.dtype == np.float32
    assert rel(single.astype(float), exact) < 1e-4


@pytest.mark.parametrize("tolerance", [1e-4, 1e-7])
def test_fast_with_rotation_within_tolerance_of_dense(tolerance):
    """The grand product (forces and torques in, velocities and rotations out) against
    the dense grand mobility's, each part within the tolerance; ``rotation=True``
    without torques gives the spins of torque-free spheres."""
    rng = np.random.default_rng(3)
    pos, radii = cloud(rng, 120, 8.0)
    f, t = rng.normal(size=(120, 3)), rng.normal(size=(120, 3))
    for torques in [t, None]:
        u0, w0 = hr.mobility_dot(pos, radii, f, torques=torques, rotation=True, method="dense")
        u, w = hr.mobility_dot(pos, radii, f, torques=torques, rotation=True, method="fast",
                               tolerance=tolerance)
        assert u.shape == w.shape == (120, 3)
        assert rel(u, u0) < tolerance and rel(w, w0) < tolerance, (rel(u, u0), rel(w, w0))
        assert rel(w, w0) > 0


def test_a_lone_sphere_moves_by_stokes_law():
    u = hr.mobility_dot([[1.0, 2.0, 3.0]], [0.7], [[0.0, 0.0, -1.0]], method="fast",
                        tolerance=1e-8, viscosity=2.0)
    assert u[0, 2] == pytest.approx(-1.0 / (6 * np.pi * 2.0 * 0.7), rel=1e-7)


@pytest.mark.parametrize(
    "kwargs, says",
    [
        (dict(box=(20.0, 20.0, 20.0)), "pse"),
        (dict(wall=-5.0), "wall"),
        (dict(hydro="oseen"), "rpy"),
        (dict(tolerance=1.0), "tolerance must be between"),
        (dict(tolerance=1e-12), "tolerance must be between"),
    ],
)
def test_what_fast_cannot_serve_is_a_value_error(kwargs, says):
    pos = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0]]
    f = np.ones((3, 3))
    with pytest.raises(ValueError, match=says):
        hr.mobility_dot(pos, [1.0, 1.0, 1.0], f, method="fast", **kwargs)


def test_a_sphere_inside_another_is_named():
    pos = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]
    with pytest.raises(ValueError, match="particle"):
        hr.mobility_dot(pos, [1.0, 0.5], np.ones((2, 3)), method="fast")


def test_an_unknown_method_lists_the_methods():
    with pytest.raises(ValueError, match="fast"):
        hr.mobility_dot([[0.0, 0.0, 0.0]], [1.0], [[1.0, 0.0, 0.0]], method="quick")
