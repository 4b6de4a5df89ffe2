"""System steps on every core: from 512 beads the kernel cuts the
mobility's work into 16 bands, which ``threads`` (0: every core, the default) runs on a
thread pool; the bits do not depend on the thread count."""

import math

import numpy as np
import pytest

import hydrorattle as hr


def helix(n):
    """``n`` unit spheres on the bench helix (radius 3, rise 2.5 a bead, three apart)."""
    phi = 2.0 * math.asin(math.sqrt(9.0 - 6.25) / 6.0)
    a = phi * np.arange(n)
    pos = np.stack([3.0 * np.cos(a), 3.0 * np.sin(a), 2.5 * np.arange(n)], axis=1)
    return pos, [[i, i + 1] for i in range(n - 1)]


@pytest.mark.parametrize(
    "params",
    [
        {},
        {"matrix_free": True},
        {"compact_products": True, "solver": "krylov"},
        {"temperature": 1.0, "seed": 5},
    ],
    ids=["stored", "matrix-free", "compact", "brownian"],
)
def test_steps_have_the_same_bits_on_one_two_and_every_core(params):
    pos, bonds = helix(720)  # banded (>= 512) and with the compact copy (>= 700)
    bits = {}
    for threads in (1, 2, 0):
        s = hr.System(pos, 1.0, 4.5, bonds=bonds, dt=0.01, threads=threads, **params)
        s.step(2)
        bits[threads] = s.state_bits()
    assert bits[2] == bits[1]
    assert bits[0] == bits[1]
    # The steps moved the chain and kept its bonds.
    assert not np.array_equal(s.positions, pos)
    assert np.abs(np.linalg.norm(np.diff(s.positions, axis=0), axis=1) - 3.0).max() < 1e-8
