"""`mobility` and `mobility_dot` above a wall and in a periodic box
against closed forms nobody here computed with the package: Hasimoto's lone sphere in
a cubic box, Faxen's and Brenner's lone sphere above a wall; the product against the
matrix; refused combinations; the same bits on any number of threads."""

import math

import numpy as np
import pytest

import hydrorattle as hr

# Hasimoto (1959): a sphere in a simple cubic lattice of spheres, to 13 digits.
HASIMOTO = 2.8372974794806


@pytest.mark.parametrize("precision,tol", [("f64", 1e-12), ("f32", 2e-6)])
def test_lone_sphere_in_a_box_is_hasimotos(precision, tol):
    for edge in [5.0, 10.0, 20.0, 50.0]:
        m = hr.mobility([[0.3, -1.0, 2.0]], [1.0], box=(edge, edge, edge), precision=precision)
        x = 1.0 / edge
        want = 1.0 - HASIMOTO * x + 4.0 * math.pi / 3.0 * x**3
        got = m * 6.0 * math.pi
        assert np.allclose(got, want * np.eye(3), rtol=0, atol=tol), (edge, got, want)


def faxen(x):
    """Parallel self mobility above a wall, x = a / h (Faxen's series)."""
    return 1 - 9 / 16 * x + x**3 / 8 - 45 / 256 * x**4 - x**5 / 16


def swan_brady_perp(x):
    """Swan & Brady's (2007) perpendicular self mobility, x = a / h."""
    return 1 - 9 / 8 * x + x**3 / 2 - x**5 / 8


@pytest.mark.parametrize("precision,tol", [("f64", 1e-12), ("f32", 2e-6)])
def test_lone_sphere_above_a_wall(precision, tol):
    wall = -0.5
    for h in [1.5, 2.0, 4.0, 10.0]:
        m = hr.mobility([[0.2, 0.1, wall + h]], [1.0], wall=wall, precision=precision)
        got = m * 6.0 * math.pi
        x = 1.0 / h
        # The RPY image system is exact to x^3: parallel, it lacks Faxen's -45/256 x^4
        # and nothing else; across, it is Swan & Brady's closed form.
        missing = 45 / 256 * x**4
        assert abs(got[0, 0] - faxen(x) - missing) < tol, (h, got[0, 0], faxen(x))
        assert abs(got[1, 1] - faxen(x) - missing) < tol
        assert abs(got[2, 2] - swan_brady_perp(x)) < tol, (h, got[2, 2])
        assert abs(got[0, 1]) < tol and abs(got[0, 2]) < tol


def spheres(rng, n, lo=1.5, hi=8.0):
    pos = rng.uniform(-hi, hi, (n, 3))
    pos[:, 2] = rng.uniform(lo, lo + 2 * hi, n)
    # Equal radii 0.5, at least 1.2 apart: no nesting.
    while True:
        d = np.linalg.norm(pos[:, None] - pos[None], axis=-1) + 9 * np.eye(n)
        bad = np.argwhere(d < 1.2)
        if len(bad) == 0:
            return pos, np.full(n, 0.5)
        pos[bad[0][0]] += rng.uniform(-2, 2, 3)
        pos[:, 2] = np.maximum(pos[:, 2], lo)


@pytest.mark.parametrize("geometry", [{"wall": 0.0}, {"box": (11.0, 13.0, 17.0)}, {}])
def test_product_is_the_matrix_times_the_forces(geometry):
    rng = np.random.default_rng(3)
    pos, radii = spheres(rng, 30)
    f = rng.normal(size=(30, 3))
    m = hr.mobility(pos, radii, **geometry)
    # In a box the default ("auto") product is PSE's, to its tolerance (test_pse.py):
    # the exact sum here.
    u = hr.mobility_dot(pos, radii, f, method="ewald", **geometry)
    assert np.allclose(u.ravel(), m @ f.ravel(), rtol=0, atol=1e-13 * np.abs(m).max() * 30)
    # Symmetric and positive definite.
    assert np.array_equal(m, m.T)
    np.linalg.cholesky(m)


def test_wall_with_rotation():
    rng = np.random.default_rng(4)
    pos, radii = spheres(rng, 6)
    f, t = rng.normal(size=(6, 3)), rng.normal(size=(6, 3))
    m = hr.mobility(pos, radii, rotation=True, wall=0.0)
    assert m.shape == (36, 36)
    u, w = hr.mobility_dot(pos, radii, f, t, wall=0.0)
    assert np.allclose(np.concatenate([u.ravel(), w.ravel()]), m @ np.concatenate([f.ravel(), t.ravel()]))
    # Far from the wall: free space's grand mobility.
    far = hr.mobility(pos, radii, rotation=True, wall=-1e7)
    free = hr.mobility(pos, radii, rotation=True)
    assert np.allclose(far, free, rtol=0, atol=1e-7 * np.abs(free).max())


def test_box_grows_into_free_space():
    rng = np.random.default_rng(5)
    pos, radii = spheres(rng, 5)
    free = hr.mobility(pos, radii)
    for edge, tol in [(400.0, 0.05), (4000.0, 0.005)]:
        m = hr.mobility(pos, radii, box=(edge, edge, edge))
        assert np.abs(m - free).max() < tol * np.abs(free).max()


def test_box_rotation_lone_sphere():
    # A lone sphere's rotational mobility in a cubic box: the images' point dipoles
    # cancel shell by shell and the excluded mean flow leaves 1 - (4 pi / 3)(a/L)^3
    # (the closed form, not the kernel's sums).
    a, edge = 1.0, 10.0
    m = hr.mobility([[0.3, -1.2, 2.0]], [a], rotation=True, box=(edge, edge, edge))
    expect = (1.0 - 4.0 * np.pi / 3.0 * (a / edge) ** 3) / (8.0 * np.pi * a**3)
    assert np.allclose(m[3:, 3:], expect * np.eye(3), rtol=1e-12, atol=1e-15)
    assert np.abs(m[:3, 3:]).max() < 1e-15


@pytest.mark.parametrize(
    "kw,what",
    [
        ({"box": (10, 10, 10), "wall": 0.0}, "wall"),
        ({"box": (10, 10, 10), "hydro": "oseen"}, "Oseen"),
        ({"box": (1.5, 10, 10)}, "radius"),
        ({"box": (0, 10, 10)}, "box"),
        ({"box": (10, 10)}, "box"),
        ({"wall": 5.0}, "wall"),
    ],
)
def test_refused_geometries(kw, what):
    pos, radii = [[0, 0, 1.0], [0, 0, 4.0]], [1.0, 1.0]
    for call in (
        lambda: hr.mobility(pos, radii, **kw),
        lambda: hr.mobility_dot(pos, radii, np.ones((2, 3)), **kw),
    ):
        with pytest.raises(ValueError, match=what):
            call()


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_threads_give_the_same_bits(precision):
    rng = np.random.default_rng(6)
    n = 700
    pos = rng.uniform(-20, 20, (n, 3))
    radii = rng.uniform(0.1, 0.3, n)
    f = rng.normal(size=(n, 3))
    one = hr.mobility_dot(pos, radii, f, threads=1, precision=precision)
    for k in [0, 2, 3]:
        assert np.array_equal(hr.mobility_dot(pos, radii, f, threads=k, precision=precision), one)
    m = hr.mobility(pos, radii, precision=precision)
    assert np.allclose(one.ravel(), m @ f.ravel(), rtol=0, atol=1e-5 * np.abs(one).max())
    small = slice(0, 300)
    u = hr.mobility_dot(pos[small], radii[small], f[small], threads=4, precision=precision)
    ms = hr.mobility(pos[small], radii[small], precision=precision)
    # Below 512 beads: the bits of the stored matrix's one-pass product (rows in order).
    assert np.allclose(u.ravel(), ms @ f[small].ravel(), rtol=1e-5 if precision == "f32" else 1e-12)


def test_threads_must_be_a_count():
    with pytest.raises(TypeError, match="threads"):
        hr.mobility_dot([[0, 0, 0]], [1.0], [[1, 0, 0]], threads=1.5)
    with pytest.raises(ValueError, match="threads"):
        hr.mobility_dot([[0, 0, 0]], [1.0], [[1, 0, 0]], threads=-1)


def test_dense_mobility_is_the_same_on_any_threads():
    rng = np.random.default_rng(8)
    n = 600
    pos = rng.uniform(-20, 20, (n, 3))
    radii = rng.uniform(0.1, 0.3, n)
    one = hr.mobility(pos, radii, threads=1)
    assert np.array_equal(hr.mobility(pos, radii, threads=3), one)
    assert np.array_equal(one, one.T)
    # The product of the same matrix, matrix-free.
    f = rng.normal(size=(n, 3))
    u = hr.mobility_dot(pos, radii, f)
    assert np.allclose(u.ravel(), one @ f.ravel(), rtol=0, atol=1e-13 * np.abs(u).max())


def test_no_spheres():
    assert hr.mobility(np.zeros((0, 3)), []).shape == (0, 0)
    assert hr.mobility_dot(np.zeros((0, 3)), [], np.zeros((0, 3))).shape == (0, 3)
