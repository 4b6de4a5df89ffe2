"""`mobility_dot` in a periodic box by PSE (``method="pse"``, and ``"auto"``'s pick):
against the exact Ewald sum (``method="ewald"``, itself checked against Hasimoto in
test_geometry.py) within the requested tolerance, on random polydisperse spheres
(overlapping pairs included) in cubic and rectangular boxes; the same bits on any number
of threads; what PSE cannot serve refused or left to the Ewald sum. The timing at
N = 10^5 is stated in docs/PYTHON.md, not tested."""

import numpy as np
import pytest

import hydrorattle as hr


def suspension(rng, n, box, overlap=True):
    """`n` spheres of radii 0.5 to 1.2 in `box`, none inside another's image; with
    `overlap`, every fifth placed overlapping an earlier one."""
    box = np.asarray(box, dtype=float)
    radii = rng.uniform(0.5, 1.2, n)
    pos = np.empty((n, 3))
    k = 0
    while k < n:
        if overlap and k > 0 and k % 5 == 0:
            j = rng.integers(k)
            d = rng.normal(size=3)
            d *= (abs(radii[j] - radii[k]) + 0.3 + rng.uniform(0, 0.5)) / np.linalg.norm(d)
            pos[k] = pos[j] + d
        else:
            pos[k] = rng.uniform(0, 1, 3) * box
        r = pos[:k] - pos[k]
        r -= box * np.round(r / box)
        dist = np.linalg.norm(r, axis=1)
        close = dist < np.abs(radii[:k] - radii[k]) + 0.05
        if overlap or not np.any(dist < radii[:k] + radii[k]):
            if not np.any(close):
                k += 1
    return pos, radii


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


@pytest.mark.parametrize("box", [(12.0, 12.0, 12.0), (9.0, 13.0, 16.0)])
@pytest.mark.parametrize("tolerance", [1e-3, 1e-4, 1e-6])
def test_pse_within_tolerance_of_ewald(box, tolerance):
    rng = np.random.default_rng(int(tolerance * 1e7) + int(box[1]))
    pos, radii = suspension(rng, 60, box)
    f = rng.normal(size=(60, 3))
    exact = hr.mobility_dot(pos, radii, f, box=box, method="ewald")
    fast = hr.mobility_dot(pos, radii, f, box=box, method="pse", tolerance=tolerance)
    err = rel(fast, exact)
    assert err < tolerance, err
    # Not the Ewald sum itself: PSE's own error is there, at the scale asked for.
    assert err > 1e-3 * tolerance, err


def test_auto_picks_pse_where_it_serves():
    rng = np.random.default_rng(11)
    box = (10.0, 11.0, 12.0)
    pos, radii = suspension(rng, 30, box)
    f, t = rng.normal(size=(30, 3)), rng.normal(size=(30, 3))
    pse = hr.mobility_dot(pos, radii, f, box=box, method="pse")
    # The default is "auto" at the scenes' default tolerance 1e-6: PSE here.
    assert np.array_equal(hr.mobility_dot(pos, radii, f, box=box), pse)
    assert np.array_equal(hr.mobility_dot(pos, radii, f, box=box, tolerance=1e-6), pse)
    assert not np.array_equal(hr.mobility_dot(pos, radii, f, box=box, method="ewald"), pse)
    # Torques or rotation: PSE has no rotation blocks, so "auto" is the Ewald sum.
    u, w = hr.mobility_dot(pos, radii, f, t, box=box)
    u2, w2 = hr.mobility_dot(pos, radii, f, t, box=box, method="ewald")
    assert np.array_equal(u, u2) and np.array_equal(w, w2)
    # Free draining: no pair interacts; "auto" leaves it to the kernel's own path.
    fd = hr.mobility_dot(pos, radii, f, box=box, hydro="free-draining")
    assert np.array_equal(fd, hr.mobility_dot(pos, radii, f, box=box, hydro="free-draining", method="ewald"))
    # A tolerance whose grid would pass the kernel's bounds: "auto" is the Ewald sum
    # (a dilute box of two small spheres at 1e-12), "pse" is refused.
    tiny = ([[1.0, 1.0, 1.0], [30.0, 40.0, 50.0]], [0.05, 0.05], np.ones((2, 3)))
    big = (100.0, 100.0, 100.0)
    exact = hr.mobility_dot(*tiny, box=big, method="ewald")
    assert np.array_equal(hr.mobility_dot(*tiny, box=big, tolerance=1e-12), exact)
    with pytest.raises(ValueError, match="grid"):
        hr.mobility_dot(*tiny, box=big, method="pse", tolerance=1e-12)


def test_f32_pse():
    rng = np.random.default_rng(12)
    box = (10.0, 10.0, 10.0)
    pos, radii = suspension(rng, 40, box)
    f = rng.normal(size=(40, 3))
    exact = hr.mobility_dot(pos, radii, f, box=box, method="ewald")
    fast = hr.mobility_dot(pos, radii, f, box=box, method="pse", tolerance=1e-4, precision="f32")
    assert fast.dtype == np.float32
    assert rel(fast.astype(float), exact) < 1e-4


def test_pse_threads_give_the_same_bits():
    rng = np.random.default_rng(13)
    box = (20.0, 20.0, 20.0)
    pos, radii = suspension(rng, 700, box, overlap=False)
    f = rng.normal(size=(700, 3))
    one = hr.mobility_dot(pos, radii, f, box=box, threads=1)
    for k in [0, 2, 3]:
        assert np.array_equal(hr.mobility_dot(pos, radii, f, box=box, threads=k), one)


@pytest.mark.parametrize(
    "kw,what",
    [
        ({"method": "quick"}, "method"),
        ({"method": "pse"}, "needs a periodic box"),
        ({"method": "pse", "box": (10, 10, 10), "rotation": True}, "translational"),
        ({"method": "pse", "box": (10, 10, 10), "hydro": "oseen"}, "rpy"),
        ({"box": (10, 10, 10), "tolerance": 0.5}, "tolerance"),
        ({"box": (10, 10, 10), "tolerance": 1e-13, "method": "ewald"}, "tolerance"),
        ({"box": (10, 10, 10), "tolerance": 0.0}, "tolerance"),
        ({"method": "pse", "box": (1.5, 10, 10)}, "radius|half"),
    ],
)
def test_refused(kw, what):
    pos, radii = [[1.0, 1.0, 1.0], [1.0, 1.0, 4.0]], [1.0, 1.0]
    with pytest.raises(ValueError, match=what):
        hr.mobility_dot(pos, radii, np.ones((2, 3)), **kw)


def test_nested_spheres_refused_by_pse():
    # A sphere inside another's image across a face: the near field refuses it.
    pos, radii = [[0.2, 5.0, 5.0], [9.9, 5.0, 5.0]], [1.0, 0.2]
    with pytest.raises(ValueError, match="inside|nested|particle"):
        hr.mobility_dot(pos, radii, np.ones((2, 3)), box=(10, 10, 10), method="pse")
