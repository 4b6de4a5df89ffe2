"""mobility_dot against a numba-parallel RPY product (the stand-in for what users write
themselves), and the dense mobility's cost per entry.

Usage: python python/bench/mobility_dot.py [N ...]   (needs numba; default 1000 4096 16384)

Prints, per N: the best of 5 wall times of hydrorattle.mobility_dot with threads=1 and
threads=0 (every core), of the numba product (compiled first, parallel over rows with
prange; each pair evaluated twice, once per row, as a row-parallel loop does), their
agreement, and the pair evaluations per second. Then hydrorattle.mobility's ns per
output entry and minor page faults per entry from N = 300 to 1500.
"""

import math
import os
import resource
import sys
import time

import numpy as np
from numba import get_num_threads, njit, prange

import hydrorattle as hr


@njit(parallel=True, fastmath=False, cache=False)
def rpy_dot(pos, a, f, eta):
    """u = M f for equal radii a: RPY, both branches (overlap below 2a)."""
    n = pos.shape[0]
    u = np.zeros((n, 3))
    self_mu = 1.0 / (6.0 * math.pi * eta * a)
    for i in prange(n):
        ux = self_mu * f[i, 0]
        uy = self_mu * f[i, 1]
        uz = self_mu * f[i, 2]
        for j in range(n):
            if j == i:
                continue
            dx = pos[i, 0] - pos[j, 0]
            dy = pos[i, 1] - pos[j, 1]
            dz = pos[i, 2] - pos[j, 2]
            r2 = dx * dx + dy * dy + dz * dz
            r = math.sqrt(r2)
            if r >= 2.0 * a:
                c = 1.0 / (8.0 * math.pi * eta * r)
                s = 2.0 * a * a / (3.0 * r2)
                iso = c * (1.0 + s)
                rr = c * (1.0 - 3.0 * s) / r2
            else:
                c = 1.0 / (6.0 * math.pi * eta * a)
                iso = c * (1.0 - 9.0 * r / (32.0 * a))
                rr = c * 3.0 / (32.0 * a * r)
            dot = dx * f[j, 0] + dy * f[j, 1] + dz * f[j, 2]
            ux += iso * f[j, 0] + rr * dx * dot
            uy += iso * f[j, 1] + rr * dy * dot
            uz += iso * f[j, 2] + rr * dz * dot
        u[i, 0] = ux
        u[i, 1] = uy
        u[i, 2] = uz
    return u


def best(fn, repeat=5):
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return min(out)


def spheres(n, seed=1):
    """Equal spheres (a = 1) at volume fraction 0.05 in a cube: some pairs overlap."""
    rng = np.random.default_rng(seed)
    edge = (n * 4.0 / 3.0 * math.pi / 0.05) ** (1 / 3)
    return rng.uniform(0, edge, (n, 3)), np.ones(n), rng.normal(size=(n, 3))


def products(sizes):
    cores = os.cpu_count()
    print(f"cores: {cores}, numba threads: {get_num_threads()}")
    print("| N | hydrorattle 1 thread | hydrorattle every core | numba every core | max rel diff | hr pairs/s (every core) |")
    print("| --- | --- | --- | --- | --- | --- |")
    rpy_dot(*spheres(10)[:1], 1.0, spheres(10)[2], 1.0)  # compile
    for n in sizes:
        pos, radii, f = spheres(n)
        repeat = 5 if n <= 4096 else 2
        t1 = best(lambda: hr.mobility_dot(pos, radii, f, threads=1), repeat)
        tk = best(lambda: hr.mobility_dot(pos, radii, f, threads=0), repeat)
        tn = best(lambda: rpy_dot(pos, 1.0, f, 1.0), repeat)
        u = hr.mobility_dot(pos, radii, f)
        v = rpy_dot(pos, 1.0, f, 1.0)
        diff = np.abs(u - v).max() / np.abs(v).max()
        pairs = n * (n - 1) / 2
        print(f"| {n} | {t1 * 1e3:.1f} ms | {tk * 1e3:.1f} ms | {tn * 1e3:.1f} ms | {diff:.1e} | {pairs / tk:.2e} |")


def dense():
    print("\n| N | mobility ns/entry | minor faults per 1000 entries |")
    print("| --- | --- | --- |")
    for n in [300, 500, 700, 1000, 1500]:
        pos, radii, _ = spheres(n)
        entries = (3 * n) ** 2
        f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        t = best(lambda: hr.mobility(pos, radii), 3)
        f1 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        print(f"| {n} | {t / entries * 1e9:.2f} | {(f1 - f0) / 3 / entries * 1e3:.2f} |")


if __name__ == "__main__":
    sizes = [int(x) for x in sys.argv[1:]] or [1000, 4096, 16384]
    products(sizes)
    dense()
