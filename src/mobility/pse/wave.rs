//! The wave-space kernel of PSE on the grid: from the transformed spread sources to the
//! transformed velocity field, mode by mode.
//!
//! At each `k` the two packed sources are separated (the transforms of real fields are
//! Hermitian, so mode `-k` recovers them: `S1 = (Z(k) + conj Z(-k)) / 2`,
//! `S2 = (Z(k) - conj Z(-k)) / (2 i)`), Beenakker's sphere factor of the source is formed
//! as `q = S1 - k^2 S2 / 6`, and
//!
//! ```text
//! u(k) = h^3 / (eta M) (1 + k^2/(4 xi^2)) exp(-k^2/(4 xi^2)) / ghat(k)^2 / k^2 (I - k k/k^2) q,
//! ```
//!
//! with `ghat(k) = exp(-sigma^2 k^2 / 2)` the spreading Gaussian's transform (divided out
//! twice: once for spreading, once for interpolation) and `M` the number of grid
//! points. The result is written back packed as `u + i k^2 u` (and its conjugate
//! partner at `-k`), so one inverse transform yields both `IFFT(u)` and `IFFT(k^2 u)`
//! for the receiving sphere's factor (`spread.rs`). The mode `k = 0` (the mean flow) and
//! the Nyquist planes of even grids (ambiguous in sign; beyond the wave-space cutoff)
//! are set to zero.

use super::Pse;
use super::fft::Cx;
use crate::real::Real;

/// Fills `table[d][n] = [k_d, exp(-(1/(4 xi^2) - sigma^2) k_d^2)]` for grid index `n`
/// (signed index `n` below `M_d / 2`, `n - M_d` above); the Nyquist entry's `k` is
/// unused.
pub(super) fn tables<T: Real>(pse: &Pse<T>, table: &mut [Cx<T>]) {
    let mut at = 0;
    for d in 0..3 {
        let (m, l) = (pse.grid.m[d], pse.cell.size()[d]);
        for n in 0..m {
            let s = if 2 * n <= m {
                n as f64
            } else {
                n as f64 - m as f64
            };
            let k = T::from_f64(2.0 * core::f64::consts::PI * s) / l;
            table[at + n] = [k, (-(pse.residual * k * k)).exp()];
        }
        at += m;
    }
}

/// Calls `f(idx, pidx, mode)` for each pair of modes `(k, -k)` once (their grid points'
/// linear indices, in ascending order of the lower), `mode` the wave vector, `k^2` and
/// the product kernel's scalar `s(k) = h^3 / (eta M) H(k) / ghat(k)^2 / k^2`
/// (`M` grid points), or `None` for the modes set to zero (`k = 0`, the self-conjugate
/// modes and the Nyquist planes).
#[inline(always)]
fn for_each_pair<T: Real>(
    pse: &Pse<T>,
    eta: T,
    table: &[Cx<T>],
    mut f: impl FnMut(usize, usize, Option<([T; 3], T, T)>),
) {
    let [mx, my, mz] = pse.grid.m;
    let (tx, rest) = table.split_at(mx);
    let (ty, tz) = rest.split_at(my);
    let total = (mx * my * mz) as f64;
    let scale = pse.cell.volume() / (eta * T::from_f64(total * total));
    let inv_4xi2 = T::ONE / (T::from_f64(4.0) * pse.xi * pse.xi);
    let nyquist = |n: usize, m: usize| 2 * n == m;
    for iz in 0..mz {
        let pz = (mz - iz) % mz;
        for iy in 0..my {
            let py = (my - iy) % my;
            for ix in 0..mx {
                let px = (mx - ix) % mx;
                let idx = ix + mx * (iy + my * iz);
                let pidx = px + mx * (py + my * pz);
                if pidx < idx {
                    continue;
                }
                if idx == pidx || nyquist(ix, mx) || nyquist(iy, my) || nyquist(iz, mz) {
                    f(idx, pidx, None);
                    continue;
                }
                let k = [tx[ix][0], ty[iy][0], tz[iz][0]];
                let k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
                let g = tx[ix][1] * ty[iy][1] * tz[iz][1];
                f(
                    idx,
                    pidx,
                    Some((k, k2, scale * (T::ONE + k2 * inv_4xi2) * g / k2)),
                );
            }
        }
    }
}

/// Replaces the transformed sources on `grid` (3 components per point) by the
/// transformed velocity field, pairs `(k, -k)` visited once, in ascending order of the
/// lower linear index.
pub(super) fn apply_kernel<T: Real>(pse: &Pse<T>, eta: T, table: &[Cx<T>], grid: &mut [Cx<T>]) {
    let sixth = T::ONE / T::from_f64(6.0);
    let half = T::HALF;
    for_each_pair(pse, eta, table, |idx, pidx, mode| {
        let (idx, pidx) = (3 * idx, 3 * pidx);
        let Some((k, k2, s)) = mode else {
            grid[idx..idx + 3].fill([T::ZERO; 2]);
            grid[pidx..pidx + 3].fill([T::ZERO; 2]);
            return;
        };
        // The source with the sphere factor, q = S1 - k^2 S2 / 6, per component.
        let mut q = [[T::ZERO; 2]; 3];
        for c in 0..3 {
            let (z, zm) = (grid[idx + c], grid[pidx + c]);
            let s1 = [(z[0] + zm[0]) * half, (z[1] - zm[1]) * half];
            let s2 = [(z[1] + zm[1]) * half, (zm[0] - z[0]) * half];
            let f = k2 * sixth;
            q[c] = [s1[0] - f * s2[0], s1[1] - f * s2[1]];
        }
        // Project across k, scale, and pack u + i k^2 u (and the partner).
        for part in 0..2 {
            let kq = (k[0] * q[0][part] + k[1] * q[1][part] + k[2] * q[2][part]) / k2;
            for c in 0..3 {
                q[c][part] = s * (q[c][part] - k[c] * kq);
            }
        }
        for c in 0..3 {
            let [ur, ui] = q[c];
            grid[idx + c] = [ur - k2 * ui, ui + k2 * ur];
            grid[pidx + c] = [ur + k2 * ui, k2 * ur - ui];
        }
    });
}

/// The grand product's kernel (six components per point: the packed forces as
/// [`apply_kernel`]'s, then the torque `T`): with `s(k)` [`apply_kernel`]'s scalar
/// (Hasimoto's `H / (eta k^2)` with the grid's factors), the velocity is
/// `s P q + (s/2) i k x T` and the spin `(s/2) i k x F + (s k^2/4) P T`: the rotation
/// blocks of the Ewald path's wave space (`periodic/rot.rs`: a force turns a sphere by
/// `i H/(2 eta k^2) k x F`, a torque by `H/(4 eta) P T`, the rotlet moves one by the
/// transpose, the same `i H/(2 eta k^2) k x T`), with no sphere factors: `F` is the
/// bare force `S1` and the receiving factor's field `V = k^2 s P q` leaves the torque's
/// velocity out. Packed back as `U + i V` (velocity) and the spin (real field).
pub(super) fn apply_kernel_grand<T: Real>(
    pse: &Pse<T>,
    eta: T,
    table: &[Cx<T>],
    grid: &mut [Cx<T>],
) {
    let sixth = T::ONE / T::from_f64(6.0);
    let (half, quarter) = (T::HALF, T::from_f64(0.25));
    let cross = |a: [T; 3], b: [T; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    // `P v` of the real or imaginary parts `v`.
    let project = |k: [T; 3], k2: T, v: [T; 3]| {
        let kv = (k[0] * v[0] + k[1] * v[1] + k[2] * v[2]) / k2;
        [v[0] - k[0] * kv, v[1] - k[1] * kv, v[2] - k[2] * kv]
    };
    for_each_pair(pse, eta, table, |idx, pidx, mode| {
        let (idx, pidx) = (6 * idx, 6 * pidx);
        let Some((k, k2, s)) = mode else {
            grid[idx..idx + 6].fill([T::ZERO; 2]);
            grid[pidx..pidx + 6].fill([T::ZERO; 2]);
            return;
        };
        let f = k2 * sixth;
        // Real and imaginary parts of the bare force S1, the sphere factor's
        // source q = S1 - k^2 S2 / 6, and the torque.
        let (mut s1, mut q, mut t) = ([[T::ZERO; 3]; 2], [[T::ZERO; 3]; 2], [[T::ZERO; 3]; 2]);
        for c in 0..3 {
            let (z, zm) = (grid[idx + c], grid[pidx + c]);
            let a = [(z[0] + zm[0]) * half, (z[1] - zm[1]) * half];
            let b = [(z[1] + zm[1]) * half, (zm[0] - z[0]) * half];
            for part in 0..2 {
                s1[part][c] = a[part];
                q[part][c] = a[part] - f * b[part];
                t[part][c] = grid[idx + 3 + c][part];
            }
        }
        let u = [project(k, k2, q[0]), project(k, k2, q[1])];
        let pt = [project(k, k2, t[0]), project(k, k2, t[1])];
        // i (k x v) = -(k x v_im) + i (k x v_re).
        let (kt, kf) = (
            [cross(k, t[0]), cross(k, t[1])],
            [cross(k, s1[0]), cross(k, s1[1])],
        );
        let (hs, qs) = (s * half, s * k2 * quarter);
        for c in 0..3 {
            let (ur, ui) = (s * u[0][c], s * u[1][c]);
            let big = [ur - hs * kt[1][c], ui + hs * kt[0][c]];
            let (vr, vi) = (k2 * ur, k2 * ui);
            grid[idx + c] = [big[0] - vi, big[1] + vr];
            grid[pidx + c] = [big[0] + vi, vr - big[1]];
            let w = [qs * pt[0][c] - hs * kf[1][c], qs * pt[1][c] + hs * kf[0][c]];
            grid[idx + 3 + c] = w;
            grid[pidx + 3 + c] = [w[0], -w[1]];
        }
    });
}

/// Replaces the transform `Z` of white noise (unit variance at every point and
/// component) by `sqrt(s(k) / M) (I - k k/k^2) Z(k)`, packed as `u + i k^2 u` like the
/// product's, with `s(k)` the product's kernel and `M` the number of grid points: the
/// interpolated field then has covariance `M^wave` exactly (the product is
/// `B^* s P B`, this is `B^* sqrt(s) P F zeta / sqrt(M)` and `F F^* = M I`). Each mode
/// alone: `Z` of a real field is Hermitian, so `u` is too.
pub(super) fn apply_sqrt_kernel<T: Real>(
    pse: &Pse<T>,
    eta: T,
    table: &[Cx<T>],
    grid: &mut [Cx<T>],
) {
    let [mx, my, mz] = pse.grid.m;
    let (tx, rest) = table.split_at(mx);
    let (ty, tz) = rest.split_at(my);
    let total = (mx * my * mz) as f64;
    let scale = pse.cell.volume() / (eta * T::from_f64(total * total * total));
    let inv_4xi2 = T::ONE / (T::from_f64(4.0) * pse.xi * pse.xi);
    let nyquist = |n: usize, m: usize| 2 * n == m;
    for iz in 0..mz {
        for iy in 0..my {
            for ix in 0..mx {
                let idx = 3 * (ix + mx * (iy + my * iz));
                let zero = (ix == 0 && iy == 0 && iz == 0)
                    || nyquist(ix, mx)
                    || nyquist(iy, my)
                    || nyquist(iz, mz);
                if zero {
                    grid[idx..idx + 3].fill([T::ZERO; 2]);
                    continue;
                }
                let k = [tx[ix][0], ty[iy][0], tz[iz][0]];
                let k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
                let g = tx[ix][1] * ty[iy][1] * tz[iz][1];
                let r = (scale * (T::ONE + k2 * inv_4xi2) * g / k2).sqrt();
                let z = &mut grid[idx..idx + 3];
                for part in 0..2 {
                    let kz = (k[0] * z[0][part] + k[1] * z[1][part] + k[2] * z[2][part]) / k2;
                    for c in 0..3 {
                        z[c][part] = r * (z[c][part] - k[c] * kz);
                    }
                }
                for v in z.iter_mut() {
                    let [ur, ui] = *v;
                    *v = [ur - k2 * ui, ui + k2 * ur];
                }
            }
        }
    }
}
