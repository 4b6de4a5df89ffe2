//! The metric read one entry at a time: `D_l(p)` for a bond and a bead, a bond's
//! relative change, a row of the constraint Jacobian, and the moves of one or every
//! multiplier added bond after bond. The sweep, the dense Newton solve and the Krylov
//! preconditioner's band read these, inlined at each call site (the Jacobian rows, the
//! moves); the metrics that compute an entry from blocks sit behind `at_far`, which is
//! called, not inlined, on 32-bit Arm.

use super::{Metric, sym_block, sym_diff_mul};
use crate::bonds::Bond;
use crate::linalg::{self, tri, with_blocks};
use crate::real::Real;

impl<T: Real> Metric<'_, T> {
    /// Displacement of bead `p` per unit multiplier on bond `l`. Exact for every metric
    /// but [`Metric::Drag`], where it is the preconditioner's local model
    /// `Q_pq ~ sqrt(c_p c_q) mu_pq`, `c_p = 1 / (1 + m_p mu_pp / dt)`: exact for a lone
    /// bead, `mu` as the masses vanish and `dt / m` as they grow.
    #[inline(always)]
    pub fn at(&self, bonds: &[Bond<T>], l: usize, p: usize) -> T::V3 {
        let b = bonds[l];
        match *self {
            Metric::Mass {
                inv_mass,
                grad,
                scale,
            } => {
                if p == b.i {
                    grad[l] * (scale * inv_mass[p])
                } else if p == b.j {
                    grad[l] * (-scale * inv_mass[p])
                } else {
                    T::V3_ZERO
                }
            }
            Metric::Dense { disp, n, .. } => disp[l * n + p],
            _ => self.at_far(bonds, l, p),
        }
    }

    /// [`Metric::at`] for the metrics that compute it (mobility blocks, matrix-free
    /// blocks, the drag model). Called, not inlined, on 32-bit Arm: `at` is inlined at
    /// every call site (the Jacobian rows, the moves) and these arms would be copied
    /// into each (~2 kB of firmware flash); the firmware's dense solves read
    /// [`Metric::Dense`] or [`Metric::Mass`], which stay inline.
    #[cfg_attr(target_arch = "arm", inline(never))]
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    fn at_far(&self, bonds: &[Bond<T>], l: usize, p: usize) -> T::V3 {
        let b = bonds[l];
        match *self {
            // Read inline by `at`, which never calls this for them.
            Metric::Mass { .. } | Metric::Dense { .. } => T::V3_ZERO,
            Metric::Mobility {
                mu, grad, scale, ..
            } => {
                let g = grad[l] * scale;
                with_blocks!(mu, mu => {
                    let mu_pj = match b.one_sphere() {
                        true => T::M3_ZERO,
                        false => sym_block::<T, _>(mu, p, b.j),
                    };
                    sym_diff_mul::<T>(sym_block::<T, _>(mu, p, b.i), mu_pj, g, false)
                })
            }
            Metric::Free {
                hydro,
                pos,
                radius,
                grad,
                scale,
                ..
            } => {
                if !hydro.has_blocks() {
                    return T::V3_ZERO;
                }
                // Nested pairs were refused by the product at these positions.
                let block = |q| hydro.block_at(pos, radius, p, q).unwrap_or(T::M3_ZERO);
                let mu_pj = if b.one_sphere() {
                    T::M3_ZERO
                } else {
                    block(b.j)
                };
                sym_diff_mul::<T>(block(b.i), mu_pj, grad[l] * scale, hydro.lower_only())
            }
            Metric::Drag {
                mu, sq, dt, grad, ..
            } => {
                let c = |q: usize| {
                    let self_mu = T::m3_get(mu[tri(q) + q], 0, 0);
                    T::ONE / (T::ONE + sq[q] * sq[q] * self_mu / dt)
                };
                let cp = c(p);
                let g = grad[l] * dt;
                let q_pi = linalg::sym_get::<T>(mu, p, b.i) * (cp * c(b.i)).sqrt();
                let q_pj = linalg::sym_get::<T>(mu, p, b.j) * (cp * c(b.j)).sqrt();
                q_pi * g - q_pj * g
            }
        }
    }

    /// Change of bond `k`'s vector per unit multiplier on bond `l`.
    #[inline(always)]
    pub fn relative(&self, bonds: &[Bond<T>], k: usize, l: usize) -> T::V3 {
        let b = bonds[k];
        if b.one_sphere() {
            return crate::bonds::component::<T>(self.at(bonds, l, b.i), b.axis());
        }
        self.at(bonds, l, b.i) - self.at(bonds, l, b.j)
    }

    /// `row[l - first] = dir . (D_l(i_k) - D_l(j_k))` for `l` in `first..first + row.len()`:
    /// a row of the constraint Jacobian. The metric is matched once per row, not per
    /// entry (this is the dense solve's inner loop).
    pub fn jacobian_row(
        &self,
        bonds: &[Bond<T>],
        k: usize,
        dir: T::V3,
        first: usize,
        row: &mut [T],
    ) {
        let b = bonds[k];
        match *self {
            Metric::Dense { disp, n, .. } => {
                let rows = disp[first * n..].chunks_exact(n);
                if b.one_sphere() {
                    // A wall link moves its sphere alone.
                    for (r, d) in row.iter_mut().zip(rows) {
                        *r = T::dot(dir, d[b.i]);
                    }
                } else {
                    for (r, d) in row.iter_mut().zip(rows) {
                        *r = T::dot(dir, d[b.i] - d[b.j]);
                    }
                }
            }
            _ => {
                for (l, r) in (first..).zip(row.iter_mut()) {
                    *r = T::dot(dir, self.relative(bonds, k, l));
                }
            }
        }
    }

    /// `x += c D_l` (one bond; the sweep and the dense Newton update).
    pub fn apply_one(&self, bonds: &[Bond<T>], l: usize, c: T, x: &mut [T::V3]) {
        match *self {
            Metric::Mass { .. } => {
                let b = bonds[l];
                x[b.i] += self.at(bonds, l, b.i) * c;
                if !b.one_sphere() {
                    x[b.j] += self.at(bonds, l, b.j) * c;
                }
            }
            Metric::Dense { disp, n, .. } => {
                for (xp, &d) in x.iter_mut().zip(&disp[l * n..(l + 1) * n]) {
                    *xp += d * c;
                }
            }
            Metric::Mobility { .. } | Metric::Free { .. } | Metric::Drag { .. } => {
                for p in 0..x.len() {
                    x[p] += self.at(bonds, l, p) * c;
                }
            }
        }
    }

    /// `x += sum_l c_l D_l`, the multipliers' moves added bond after bond (the bits of
    /// [`Metric::apply_one`] for `l = 0, 1, ...`; the dense Newton update). The table
    /// is read four beads at a time: their twelve running sums stay in registers and
    /// adjacent beads' coordinates are adjacent in memory, so the compiler pairs them
    /// into packed SIMD operations (no reordering: the same bits).
    pub fn apply_each(&self, bonds: &[Bond<T>], c: &[T], x: &mut [T::V3]) {
        match *self {
            Metric::Dense { disp, n, .. } => {
                const W: usize = 4;
                let rows = || disp.chunks_exact(n).zip(c);
                let mut chunks = x.chunks_exact_mut(W);
                for (k, xs) in (&mut chunks).enumerate() {
                    let mut acc = [xs[0], xs[1], xs[2], xs[3]];
                    for (row, &cl) in rows() {
                        let d = &row[k * W..k * W + W];
                        for (a, &dp) in acc.iter_mut().zip(d) {
                            *a += dp * cl;
                        }
                    }
                    xs.copy_from_slice(&acc);
                }
                let first = x.len() - x.len() % W;
                for (p, xp) in x.iter_mut().enumerate().skip(first) {
                    let mut acc = *xp;
                    for (row, &cl) in rows() {
                        acc += row[p] * cl;
                    }
                    *xp = acc;
                }
            }
            _ => {
                for (l, &cl) in c.iter().enumerate().take(bonds.len()) {
                    self.apply_one(bonds, l, cl, x);
                }
            }
        }
    }
}
