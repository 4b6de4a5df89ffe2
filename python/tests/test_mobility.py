"""The mobility against an independent implementation (pygrpy) and closed forms."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hydrorattle as hr

pygrpy = pytest.importorskip("pygrpy.grpy_tensors")


def random_spheres(rng, n):
    """Polydisperse spheres, some pairs overlapping, none nested."""
    while True:
        radii = rng.uniform(0.5, 2.0, n)
        pos = rng.uniform(-1.5, 1.5, (n, 3)) * n ** (1 / 3) * 1.2
        d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
        gap = np.abs(radii[:, None] - radii[None])
        np.fill_diagonal(d, np.inf)
        if (d > gap * 1.05 + 1e-3).all():
            overlapping = (d < radii[:, None] + radii[None]).sum() // 2
            return pos, radii, overlapping


def rel_error(got, want):
    return np.max(np.abs(got - want)) / np.max(np.abs(want))


@pytest.mark.parametrize("precision,tol", [("f64", 1e-12), ("f32", 1e-5)])
def test_grand_mobility_matches_pygrpy(precision, tol):
    rng = np.random.default_rng(17)
    overlaps = 0
    for n in [2, 3, 5, 8, 13, 20]:
        for _ in range(5):
            pos, radii, k = random_spheres(rng, n)
            overlaps += k
            want = pygrpy.mu(pos, radii)  # eta = 1; translations then rotations
            got = hr.mobility(pos, radii, rotation=True, precision=precision)
            assert got.dtype == (np.float32 if precision == "f32" else np.float64)
            assert got.shape == (6 * n, 6 * n)
            assert rel_error(got.astype(np.float64), want) <= tol
            tt = hr.mobility(pos, radii, precision=precision)
            assert rel_error(tt.astype(np.float64), want[: 3 * n, : 3 * n]) <= tol
    assert overlaps >= 10, "the overlapping RPY branch must be exercised"


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 12), eta=st.floats(0.1, 10.0))
def test_viscosity_scales_pygrpy(seed, n, eta):
    pos, radii, _ = random_spheres(np.random.default_rng(seed), n)
    got = hr.mobility(pos, radii, viscosity=eta, rotation=True)
    assert rel_error(got, pygrpy.mu(pos, radii) / eta) <= 1e-12


def test_lone_sphere_is_stokes():
    for a, eta in [(1.0, 1.0), (0.3, 2.5), (7.0, 1e-3)]:
        m = hr.mobility([[1.0, -2.0, 3.0]], [a], viscosity=eta, rotation=True)
        assert m[:3, :3] == pytest.approx(np.eye(3) / (6 * math.pi * eta * a), rel=1e-15)
        assert m[3:, 3:] == pytest.approx(np.eye(3) / (8 * math.pi * eta * a**3), rel=1e-15)
        assert np.all(m[:3, 3:] == 0)


def test_far_pair_is_the_rpy_closed_form():
    # Unequal spheres a1, a2 at distance r > a1 + a2: mu_12 = A I + B e e^T with
    # A = (1 + (a1^2 + a2^2) / (3 r^2)) / (8 pi r), B = (1 - (a1^2 + a2^2) / r^2) / (8 pi r).
    a1, a2, r = 1.0, 2.0, 4.5
    e = np.array([2.0, -1.0, 2.0]) / 3.0
    m = hr.mobility([[0, 0, 0], r * e], [a1, a2])
    s = a1 * a1 + a2 * a2
    want = (1 + s / (3 * r * r)) / (8 * math.pi * r) * np.eye(3)
    want += (1 - s / (r * r)) / (8 * math.pi * r) * np.outer(e, e)
    assert m[:3, 3:] == pytest.approx(want, rel=1e-14, abs=1e-17)
    assert np.array_equal(m, m.T)
    assert np.linalg.eigvalsh(m).min() > 0


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_mobility_dot_is_the_matrix_times_the_forces(precision):
    pos, radii, _ = random_spheres(np.random.default_rng(3), 9)
    rng = np.random.default_rng(4)
    f, t = rng.normal(size=(9, 3)), rng.normal(size=(9, 3))
    tol = 1e-13 if precision == "f64" else 1e-5
    m = hr.mobility(pos, radii, precision=precision).astype(np.float64)
    u = hr.mobility_dot(pos, radii, f, precision=precision)
    assert u.shape == (9, 3)
    assert rel_error(u.ravel(), m @ f.ravel()) <= tol
    g = hr.mobility(pos, radii, rotation=True, precision=precision).astype(np.float64)
    u, w = hr.mobility_dot(pos, radii, f, t, precision=precision)
    uw = g @ np.concatenate([f.ravel(), t.ravel()])
    assert rel_error(np.concatenate([u.ravel(), w.ravel()]), uw) <= tol


def test_layouts_and_dtypes_are_converted():
    pos, radii, _ = random_spheres(np.random.default_rng(5), 6)
    want = hr.mobility(pos, radii)
    assert np.array_equal(hr.mobility(np.asfortranarray(pos), radii), want)
    assert np.array_equal(hr.mobility(pos.tolist(), list(radii)), want)
    big = np.zeros((6, 6))
    big[:, ::2] = pos
    assert np.array_equal(hr.mobility(big[:, ::2], radii), want)
    assert np.array_equal(hr.mobility(pos.astype(np.float32), radii.astype(np.float32)),
                          hr.mobility(pos.astype(np.float32).astype(np.float64),
                                      radii.astype(np.float32).astype(np.float64)))


@pytest.mark.parametrize(
    "pos,radii,match",
    [
        ([[0, 0, 0], [3, 0, 0]], [1, 0], "particle 1: radius"),
        ([[0, 0, 0], [3, 0, 0]], [1, -2], "particle 1: radius"),
        ([[0, 0, 0], [3, np.nan, 0]], [1, 1], "particle 1: non-finite"),
        ([[0, 0, 0], [3, 0, 0], [0, np.inf, 0]], [1, 1, 1], "particle 2: non-finite"),
        ([[0, 0, 0], [3, 0, 0], [0.5, 0, 0]], [1, 1, 2], "particles 0 and 2: one sphere inside"),
        ([[0, 0, 0], [3, 0, 0]], [1, 1, 1], r"radii must have shape \(2,\)"),
        ([[0, 0], [3, 0]], [1, 1], r"shape \(N, 3\)"),
    ],
)
def test_bad_input_raises_value_error_naming_the_particle(pos, radii, match):
    with pytest.raises(ValueError, match=match):
        hr.mobility(pos, radii)
    with pytest.raises(ValueError, match=match):
        hr.mobility_dot(pos, radii, np.zeros((len(pos), 3)))


def test_bad_options_are_refused():
    with pytest.raises(ValueError, match="viscosity"):
        hr.mobility([[0, 0, 0]], [1], viscosity=0.0)
    with pytest.raises(ValueError, match="hydro"):
        hr.mobility([[0, 0, 0]], [1], hydro="stokesian")
    with pytest.raises(ValueError, match="precision"):
        hr.mobility([[0, 0, 0]], [1], precision="f16")
    with pytest.raises(ValueError, match="particle 0: non-finite forces"):
        hr.mobility_dot([[0, 0, 0]], [1], [[np.nan, 0, 0]])
