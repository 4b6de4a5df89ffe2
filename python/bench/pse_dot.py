"""mobility_dot in a periodic box by PSE: time against N.

Usage: python python/bench/pse_dot.py N THREADS [METHOD [TOLERANCE]]
(METHOD "auto" by default: PSE at the scenes' tolerance 1e-6; "ewald" for the exact sum)

Unit spheres at random (overlaps allowed) at volume fraction 0.1 in a cubic box, random
forces, f64. Prints the best of 2 calls: wall time and the process's CPU time (on a
shared machine the CPU time is the number to read).
"""

import sys
import time

import numpy as np

import hydrorattle as hr

n, threads = int(sys.argv[1]), int(sys.argv[2])
method = sys.argv[3] if len(sys.argv) > 3 else "auto"
tol = float(sys.argv[4]) if len(sys.argv) > 4 else None
edge = (n * 4 / 3 * np.pi / 0.1) ** (1 / 3)
rng = np.random.default_rng(1)
pos = rng.uniform(0, edge, (n, 3))
radii = np.ones(n)
f = rng.normal(size=(n, 3))
best, cpu = 1e9, 1e9
for _ in range(2):
    t, c = time.perf_counter(), time.process_time()
    hr.mobility_dot(pos, radii, f, box=(edge,) * 3, threads=threads, method=method, tolerance=tol)
    best, cpu = min(best, time.perf_counter() - t), min(cpu, time.process_time() - c)
print(f"N {n} threads {threads} method {method} tolerance {tol}: {best:.3f} s wall, {cpu:.3f} s CPU")
