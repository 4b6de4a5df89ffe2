"""The NumPy + pygrpy peer of the kernel's overdamped HydroSHAKE step.

The same step as `hydrorattle`'s `Method::Overdamped` (src/integrate/overdamped.rs), written
the way a Python user would: pygrpy's vectorised RPY translational mobility
(`pygrpy.grpy_tensors.muTT`), NumPy linear algebra, Newton on the bond constraints.

    r*  = r + dt mu(r) F                       (F: buoyant weight, no flow)
    r'  = r* + dt mu(r) G(r)^T lambda          (G: the start-of-step bond vectors)
    |r'_i - r'_j| = d_ij for every bond, to a relative length error <= tol

Newton uses the exact Jacobian at the current iterate and stops as the kernel does: the
largest | |r_ij| - d | / d at most `tol`, at most `max_iterations` iterations.

Used by bench/peer/compare.py, which checks this trajectory against `host-demo run` over a
few steps and times both in one run. Needs numpy and pygrpy (pip).
"""

import numpy as np
from pygrpy.grpy_tensors import muTT


def read_xyz_frames(path):
    """Frames of an extended XYZ file written by `host-demo run`: a list of
    (time, positions (n, 3), radii (n,), masses (n,))."""
    frames = []
    with open(path) as f:
        while True:
            head = f.readline()
            if not head:
                return frames
            n = int(head)
            props = f.readline()
            time = float(props.split("Time=")[1].split()[0])
            rows = [f.readline().split() for _ in range(n)]
            pos = np.array([[float(v) for v in r[1:4]] for r in rows])
            radius = np.array([float(r[5]) for r in rows])
            mass = np.array([float(r[6]) for r in rows])
            frames.append((time, pos, radius, mass))


class OverdampedChain:
    """A chain of beads (bonds i -- i+1) stepped by the overdamped HydroSHAKE step."""

    def __init__(self, pos, radius, weight, length, dt, eta=1.0, tol=1e-12, max_iterations=50):
        if eta != 1.0:
            raise ValueError("pygrpy's muTT is for unit viscosity")
        self.pos = np.array(pos, dtype=float)
        self.radius = np.array(radius, dtype=float)
        self.force = np.array(weight, dtype=float).reshape(-1)  # (3n,)
        self.length = np.array(length, dtype=float)
        self.dt, self.tol, self.max_iterations = dt, tol, max_iterations
        n = len(self.radius)
        self.i = np.arange(n - 1)
        self.j = self.i + 1
        self.iterations = 0

    def residual(self, x):
        rel = x[self.i] - x[self.j]
        return np.max(np.abs(np.sqrt(np.einsum("kc,kc->k", rel, rel)) - self.length) / self.length)

    def step(self):
        dt, n, nb = self.dt, len(self.radius), len(self.length)
        r = self.pos
        # pygrpy returns the (n, n, 3, 3) block tensor: flattened to (3n, 3n).
        mu = muTT(r, self.radius).transpose(0, 2, 1, 3).reshape(3 * n, 3 * n)
        free = r + dt * (mu @ self.force).reshape(n, 3)
        g = r[self.i] - r[self.j]  # start-of-step bond vectors (nb, 3)
        # G^T as a (3n, nb) matrix: column l holds +g_l at bead i_l, -g_l at bead j_l.
        gt = np.zeros((n, 3, nb))
        gt[self.i, :, np.arange(nb)] = g
        gt[self.j, :, np.arange(nb)] = -g
        disp = dt * (mu @ gt.reshape(3 * n, nb))  # bead displacement per unit multiplier
        disp3 = disp.reshape(n, 3, nb)
        rel_disp = disp3[self.i] - disp3[self.j]  # (nb, 3, nb): bond k's change per lambda_l
        lam = np.zeros(nb)
        x = free
        d2 = self.length**2
        for it in range(self.max_iterations + 1):
            if self.residual(x) <= self.tol:
                self.pos = x
                self.iterations += it
                return it
            if it == self.max_iterations:
                break
            rel = x[self.i] - x[self.j]
            c = np.einsum("kc,kc->k", rel, rel) - d2
            jac = 2.0 * np.einsum("kc,kcl->kl", rel, rel_disp)
            lam += np.linalg.solve(jac, -c)
            x = free + (disp @ lam).reshape(n, 3)
        raise RuntimeError("Newton did not converge")
