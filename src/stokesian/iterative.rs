//! The Stokesian dynamics product `U = M_SD F = (M_far^-1 + R_near)^-1 F` without
//! forming `M_SD`: for many spheres, where the dense inversions of [`super::mobility`]
//! cost `O(N^3)`.
//!
//! **Formulation.** Each close pair's correction is factored, `R_p = L_p L_p^T`
//! (12x12, semi-definite Cholesky: a dependent row gets a zero column), so that
//! `R_near = L L^T` with `L` sparse (`6N x 12P`). Woodbury's identity then gives
//!
//! `M_SD = M - M L (I + L^T M L)^-1 L^T M`,
//!
//! and the product is `U = M (F - L y)` with `y` the solution of the symmetric positive
//! definite system `S y = L^T M F`, `S = I + L^T M L` (size `12P`), by preconditioned
//! conjugate gradients. Why this form: `M_far` appears only in products (one per
//! iteration, plus two), never inverted; without close pairs there is nothing to solve
//! and the product is the far field's (the far field's own conditioning never enters,
//! as it does in `M_far + M_far R M_far` or FSD's saddle point); and the unknowns live
//! on the close pairs only.
//!
//! **Preconditioner.** Block Jacobi over pairs: `B_p = I + L_p^T M_pp L_p`, with `M_pp`
//! the pair's own free-space RPY 12x12 mobility, inverted once. An isolated pair is
//! solved exactly, so the lubrication's `1/gap` stiffness leaves the iteration; what
//! remains is the coupling of pairs through shared spheres and the far field.
//!
//! **Far field.** The caller's product `u = M_far f` over the `2N` vectors (forces then
//! torques in, velocities then spins out, the grand mobility's layout): matrix-free
//! sums, or [`packed_product`] of an assembled grand mobility.
//!
//! **Storage** ([`Storage`], sized by [`sizes`] from the number of close pairs that
//! [`count_pairs`] finds) is the caller's; the close pairs are found through the cell
//! list (`O(N)`), in the order of the all-pairs loop, so the bits are the same on every
//! run. Not converging within the iterations given is [`SdError::NotConverged`]. The
//! wall's sphere corrections are not in this path (free space and the box only).

use super::{Far, NearField, SdError, pair_correction, pair_far};
use crate::cell_list::{self, CellList};
use crate::linalg::{cholesky_dense, spd_inverse};
use crate::real::Real;

/// Entries of one pair's 12x12 matrix.
const B: usize = 144;
/// Unknowns per pair.
const K: usize = 12;

/// The far field's product `u = M_far f` over the `2n` vectors (forces then torques in,
/// velocities then spins out).
pub type FarProduct<'f, T> =
    dyn FnMut(&[<T as Real>::V3], &mut [<T as Real>::V3]) -> Result<(), SdError> + 'f;

/// What [`Solver::product`] needs for `n` spheres and `pairs` close pairs:
/// `(pairs, pair reals, sphere vectors, cell-list indices)`.
pub fn sizes(n: usize, pairs: usize) -> (usize, usize, usize, usize) {
    let reals = pairs.saturating_mul(2 * B + 5 * K);
    (pairs, reals, 6usize.saturating_mul(n), 3 * n + 1)
}

/// The caller's storage for the iterative product.
pub struct Storage<'a, T: Real> {
    /// The close pairs `(i, j)`, `j < i`.
    pub pairs: &'a mut [[usize; 2]],
    /// Per pair: `L_p`, the preconditioner's block, and the five Krylov vectors.
    pub reals: &'a mut [T],
    /// `6n` vectors: the far field's input, output and the right-hand side.
    pub field: &'a mut [T::V3],
    /// The cell list's indices (`3n + 1`).
    pub cells: &'a mut [usize],
}

/// How the solve went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Report {
    /// Close pairs corrected.
    pub pairs: usize,
    /// Conjugate-gradient iterations (far-field products: this plus two).
    pub iterations: u32,
    /// The relative residual reached.
    pub residual: f64,
}

/// Calls `f(i, j)` for every pair `j < i` inside the near field's cutoff, in the
/// all-pairs loop's order (through the cell list from its size on).
fn each_pair<T: Real>(
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    cells: &mut [usize],
    mut f: impl FnMut(usize, usize) -> Result<(), SdError>,
) -> Result<(), SdError> {
    let mut close = |i: usize, j: usize| -> Result<(), SdError> {
        match super::gap(far, pos, radius, i, j).0 < near.cutoff {
            true => f(i, j),
            false => Ok(()),
        }
    };
    let a_max = cell_list::largest(radius);
    let reach = a_max * (T::TWO + near.cutoff);
    #[cfg(feature = "periodic")]
    let cell = match far {
        Far::Box(e) => Some(e.cell()),
        _ => None,
    };
    #[cfg(not(feature = "periodic"))]
    let cell = None;
    match CellList::build(pos, cell.as_ref(), reach, cells) {
        Some((list, row)) => {
            for i in 0..pos.len() {
                for &j in list.below::<T>(i, pos[i], row) {
                    close(i, j)?;
                }
            }
        }
        None => {
            for i in 0..pos.len() {
                for j in 0..i {
                    close(i, j)?;
                }
            }
        }
    }
    Ok(())
}

/// The number of close pairs (what [`sizes`] takes), with `cells` ([`sizes`]) as the
/// cell list's scratch.
pub fn count_pairs<T: Real>(
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    cells: &mut [usize],
) -> Result<usize, SdError> {
    near.check()?;
    let mut k = 0;
    each_pair(far, pos, radius, near, cells, |_, _| {
        k += 1;
        Ok(())
    })?;
    Ok(k)
}

/// `u = M f` for a packed symmetric grand mobility of `n` spheres (as
/// [`Far::assemble_grand`] stores it).
pub fn packed_product<T: Real>(packed: &[T::M3], n: usize, f: &[T::V3], u: &mut [T::V3]) {
    crate::linalg::sym_matvec::<T>(packed, 2 * n, f, u);
}

/// The factored near field of one configuration, ready for products.
pub struct Solver<'a, T: Real> {
    n: usize,
    npairs: usize,
    pairs: &'a [[usize; 2]],
    factors: &'a mut [T],
    krylov: &'a mut [T],
    field: &'a mut [T::V3],
}

/// The `V3` slot (in the grand layout) of entry `b` (0..4) of pair `(i, j)`.
#[inline(always)]
fn slot(n: usize, [i, j]: [usize; 2], b: usize) -> usize {
    [i, j, n + i, n + j][b]
}

impl<'a, T: Real> Solver<'a, T> {
    /// Finds the close pairs of the spheres, factors their corrections and the
    /// preconditioner's blocks into `store`.
    pub fn new(
        eta: T,
        far: Far<'_, T>,
        pos: &[T::V3],
        radius: &[T],
        near: NearField<T>,
        store: Storage<'a, T>,
    ) -> Result<Self, SdError> {
        near.check()?;
        let n = pos.len().min(radius.len());
        let (pos, radius) = (&pos[..n], &radius[..n]);
        if far.wall().is_some() {
            return Err(SdError::Params);
        }
        let Storage {
            pairs,
            reals,
            field,
            cells,
        } = store;
        let mut np = 0;
        each_pair(far, pos, radius, near, cells, |i, j| {
            *pairs.get_mut(np).ok_or(SdError::Storage)? = [i, j];
            np += 1;
            Ok(())
        })?;
        let (_, nr, nf, _) = sizes(n, np);
        if reals.len() < nr || field.len() < nf {
            return Err(SdError::Storage);
        }
        let (factors, krylov) = reals[..nr].split_at_mut(np * 2 * B);
        for (p, fac) in factors.chunks_exact_mut(2 * B).enumerate() {
            let [i, j] = pairs[p];
            // The correction seen from `j` to `i` (`j < i`): rows `(j, i, rot j, rot i)`.
            let c = pair_correction(eta, far, pos, radius, near, (j, i))?;
            pairs[p] = [j, i];
            let (l, b) = fac.split_at_mut(B);
            match c {
                Some(c) => {
                    for (k, x) in l.iter_mut().enumerate() {
                        *x = T::m3_get(c[k / 36][(k % K) / 3], (k / K) % 3, k % 3);
                    }
                    factor_semidefinite(l)?;
                }
                // Coincident centres: no correction (as the dense path).
                None => l.fill(T::ZERO),
            }
            precondition(eta, far, pos, radius, near, [j, i], l, b)?;
        }
        let pairs: &'a [[usize; 2]] = pairs;
        Ok(Self {
            n,
            npairs: np,
            pairs: &pairs[..np],
            factors,
            krylov,
            field: &mut field[..nf],
        })
    }

    /// The close pairs found.
    pub fn pairs(&self) -> usize {
        self.npairs
    }

    /// `u = M_SD f` (`2n` vectors each, forces then torques, velocities then spins) with
    /// the far field's product `far`, to the relative residual `tol` within `max_iter`
    /// iterations.
    pub fn product(
        &mut self,
        far: &mut FarProduct<'_, T>,
        f: &[T::V3],
        u: &mut [T::V3],
        tol: T,
        max_iter: u32,
    ) -> Result<Report, SdError> {
        let (n, np) = (self.n, self.npairs);
        let (f, u) = match (f.get(..2 * n), u.get_mut(..2 * n)) {
            (Some(f), Some(u)) => (f, u),
            _ => return Err(SdError::Storage),
        };
        if !(tol > T::ZERO && tol.is_finite()) {
            return Err(SdError::Params);
        }
        let (x, w) = self.field.split_at_mut(2 * n);
        let w = &mut w[..2 * n];
        far(f, u)?;
        let mut report = Report {
            pairs: np,
            iterations: 0,
            residual: 0.0,
        };
        if np == 0 {
            return Ok(report);
        }
        let (y, rest) = self.krylov.split_at_mut(np * K);
        let (r, rest) = rest.split_at_mut(np * K);
        let (s, rest) = rest.split_at_mut(np * K);
        let (p, q) = rest.split_at_mut(np * K);
        let ctx = (n, self.pairs, &*self.factors);
        gather(ctx, u, r);
        y.fill(T::ZERO);
        let g = dot(r, r).sqrt();
        if g > T::ZERO {
            precond(ctx, r, s);
            p.copy_from_slice(s);
            let mut rs = dot(r, s);
            loop {
                if report.iterations >= max_iter {
                    return Err(SdError::NotConverged {
                        iterations: report.iterations,
                        residual: report.residual,
                    });
                }
                report.iterations += 1;
                // q = S p = p + L^T M L p.
                scatter(ctx, p, x);
                far(x, w)?;
                gather(ctx, w, q);
                for (q, &p) in q.iter_mut().zip(p.iter()) {
                    *q += p;
                }
                let alpha = rs / dot(p, q);
                if !alpha.is_finite() {
                    return Err(SdError::NotConverged {
                        iterations: report.iterations,
                        residual: f64::NAN,
                    });
                }
                axpy(alpha, p, y);
                axpy(-alpha, q, r);
                let res = dot(r, r).sqrt() / g;
                report.residual = res.to_f64();
                if res <= tol {
                    break;
                }
                precond(ctx, r, s);
                let rs_new = dot(r, s);
                let beta = rs_new / rs;
                rs = rs_new;
                for (p, &s) in p.iter_mut().zip(s.iter()) {
                    *p = s + beta * *p;
                }
            }
        }
        // U = M (F - L y).
        scatter(ctx, y, x);
        for (x, &f) in x.iter_mut().zip(f) {
            *x = f - *x;
        }
        far(x, u)?;
        Ok(report)
    }
}

type Ctx<'c, T> = (usize, &'c [[usize; 2]], &'c [T]);

fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    a.iter().zip(b).fold(T::ZERO, |s, (&a, &b)| s + a * b)
}

fn axpy<T: Real>(a: T, x: &[T], y: &mut [T]) {
    for (y, &x) in y.iter_mut().zip(x) {
        *y += a * x;
    }
}

/// Pair `p`'s `L_p` and preconditioner `B_p^-1` as fixed-size blocks (always there:
/// the storage holds `2 B` reals a pair).
#[inline(always)]
fn blocks<T: Real>(fac: &[T], p: usize) -> Option<(&[T; B], &[T; B])> {
    let (l, rest) = fac.get(p * 2 * B..)?.split_first_chunk::<B>()?;
    Some((l, rest.first_chunk::<B>()?))
}

/// `x = L v` over the sphere vectors (`2n`).
fn scatter<T: Real>((n, pairs, fac): Ctx<'_, T>, v: &[T], x: &mut [T::V3]) {
    x.fill(T::V3_ZERO);
    for (p, (&pair, v)) in pairs.iter().zip(v.chunks_exact(K)).enumerate() {
        let Some((l, _)) = blocks(fac, p) else {
            continue;
        };
        let mut w = [T::ZERO; K];
        for k in 0..K {
            let mut s = T::ZERO;
            for m in 0..=k {
                s += l[k * K + m] * v[m];
            }
            w[k] = s;
        }
        for b in 0..4 {
            x[slot(n, pair, b)] += T::v3(w[3 * b], w[3 * b + 1], w[3 * b + 2]);
        }
    }
}

/// `g = L^T u`, pair by pair.
fn gather<T: Real>((n, pairs, fac): Ctx<'_, T>, u: &[T::V3], g: &mut [T]) {
    for (p, (&pair, g)) in pairs.iter().zip(g.chunks_exact_mut(K)).enumerate() {
        let Some((l, _)) = blocks(fac, p) else {
            continue;
        };
        let mut loc = [T::ZERO; K];
        for b in 0..4 {
            loc[3 * b..3 * b + 3].copy_from_slice(&T::xyz(u[slot(n, pair, b)]));
        }
        let mut out = [T::ZERO; K];
        for k in 0..K {
            for m in 0..=k {
                out[m] += l[k * K + m] * loc[k];
            }
        }
        g.copy_from_slice(&out);
    }
}

/// `s = B^-1 r`, pair by pair (the stored inverse).
fn precond<T: Real>((_, _, fac): Ctx<'_, T>, r: &[T], s: &mut [T]) {
    for (p, (r, s)) in r.chunks_exact(K).zip(s.chunks_exact_mut(K)).enumerate() {
        let Some((_, b)) = blocks(fac, p) else {
            continue;
        };
        for k in 0..K {
            let mut t = T::ZERO;
            for m in 0..K {
                t += b[k * K + m] * r[m];
            }
            s[k] = t;
        }
    }
}

/// `l` (a semi-definite 12x12, row-major) into its lower Cholesky factor, strict upper
/// part zero; a dependent row's column is zero.
fn factor_semidefinite<T: Real>(l: &mut [T]) -> Result<(), SdError> {
    let floor = T::EPSILON * T::from_f64(64.0);
    cholesky_dense(l, K, floor).map_err(SdError::NotPositiveDefinite)?;
    for k in 0..K {
        let d = l[k * K + k];
        l[k * K + k] = if d == T::ZERO { T::ZERO } else { T::ONE / d };
        l[k * K + k + 1..(k + 1) * K].fill(T::ZERO);
    }
    Ok(())
}

/// The preconditioner's block `(I + L^T M_pp L)^-1` of one pair into `b`.
#[allow(clippy::too_many_arguments)]
fn precondition<T: Real>(
    eta: T,
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    [i, j]: [usize; 2],
    l: &[T],
    b: &mut [T],
) -> Result<(), SdError> {
    let (a1, a2) = (radius[i], radius[j]);
    let r = far.separation(pos[i], pos[j]);
    let len = T::norm2(r).sqrt();
    // At the clamped gap, as the correction is (apart, so RPY's pair is positive definite).
    let (mean, floor) = ((a1 + a2) * T::HALF, near.min_gap + T::TWO);
    let d = match len > T::ZERO {
        true => r * ((len.max(mean * floor)) / len),
        false => T::v3(mean * floor, T::ZERO, T::ZERO),
    };
    let m = pair_far(eta, a1, a2, d);
    let mp = |k: usize, c: usize| T::m3_get(m[k / 3][c / 3], k % 3, c % 3);
    // t = M_pp L, then b = I + L^T t.
    let mut t = [T::ZERO; B];
    for k in 0..K {
        for c in 0..K {
            t[k * K + c] = (c..K).fold(T::ZERO, |s, q| s + mp(k, q) * l[q * K + c]);
        }
    }
    for k in 0..K {
        for c in 0..K {
            let v = (k..K).fold(T::ZERO, |s, q| s + l[q * K + k] * t[q * K + c]);
            b[k * K + c] = v + if k == c { T::ONE } else { T::ZERO };
        }
    }
    // Symmetric in exact arithmetic; its inverse, by the kernel's Cholesky.
    spd_inverse(b, K).map_err(SdError::NotPositiveDefinite)
}
