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
//! run. Not converging within the iterations given is [`SdError::NotConverged`].
//!
//! **The wall.** Above the wall ([`Far::above`], the far field's grand mobility then
//! the wall's), each sphere inside [`NearField::wall_cutoff`] is one more entry after
//! the pairs, `[i, i]`: its 6x6 correction ([`super::wall_correction`], the dense
//! path's) factored as a pair's is, in the translation and rotation slots of a 12x12
//! entry (the other six rows zero, their unknowns stay zero), and its preconditioner's
//! block `I + L^T M_ww L` with `M_ww` the sphere's own 6x6 wall mobility: an isolated
//! sphere near the wall is solved exactly, as an isolated pair is. The entries count
//! with the pairs ([`count_pairs`], [`Report::pairs`]).

mod noise;
mod pairs;

use super::{Far, NearField, SdError, pair_correction};
use crate::cell_list::{self, CellList};
use crate::real::Real;
use pairs::{
    axpy, dot, factor_semidefinite, gather, pair_block, precond, precondition, scatter, wall_factor,
};

/// Entries of one pair's 12x12 matrix.
pub(crate) const B: usize = 144;
/// Unknowns per pair.
pub(crate) const K: usize = 12;

/// The far field's product `u = M_far f` over the `2n` vectors (forces then torques in,
/// velocities then spins out).
pub type FarProduct<'f, T> =
    dyn FnMut(&[<T as Real>::V3], &mut [<T as Real>::V3]) -> Result<(), SdError> + 'f;

/// What [`Solver::product`] needs for `n` spheres and `pairs` entries (close pairs and
/// spheres near the wall, [`count_pairs`]):
/// `(pairs, pair reals, sphere vectors, cell-list indices)`.
pub fn sizes(n: usize, pairs: usize) -> (usize, usize, usize, usize) {
    let reals = pairs.saturating_mul(2 * B + 5 * K);
    (pairs, reals, 6usize.saturating_mul(n), 3 * n + 1)
}

/// The caller's storage for the iterative product.
pub struct Storage<'a, T: Real> {
    /// The close pairs `(i, j)`, `j < i`, then the spheres near the wall `(i, i)`.
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
    /// Entries corrected: close pairs and spheres near the wall.
    pub pairs: usize,
    /// Conjugate-gradient iterations (far-field products: this plus two).
    pub iterations: u32,
    /// The relative residual reached.
    pub residual: f64,
}

/// Calls `f(i, j)` for every pair `j < i` inside the near field's cutoff, in the
/// all-pairs loop's order (through the cell list from its size on), then `f(i, i)` for
/// every sphere inside the wall's cutoff, in order.
fn each_entry<T: Real>(
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
    let cell = far.cell();
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
    let Some(h) = far.wall() else {
        return Ok(());
    };
    for i in 0..pos.len().min(radius.len()) {
        if super::wall::gap(h, pos[i], radius[i]) < near.wall_cutoff {
            f(i, i)?;
        }
    }
    Ok(())
}

/// The number of close pairs and spheres near the wall (what [`sizes`] takes), with
/// `cells` ([`sizes`]) as the cell list's scratch.
pub fn count_pairs<T: Real>(
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    cells: &mut [usize],
) -> Result<usize, SdError> {
    near.check()?;
    let mut k = 0;
    each_entry(far, pos, radius, near, cells, |_, _| {
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

impl<'a, T: Real> Solver<'a, T> {
    /// Finds the close pairs of the spheres and those near the wall, factors their
    /// corrections and the preconditioner's blocks into `store`.
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
        let Storage {
            pairs,
            reals,
            field,
            cells,
        } = store;
        let mut np = 0;
        each_entry(far, pos, radius, near, cells, |i, j| {
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
            let (l, b) = fac.split_at_mut(B);
            if let (true, Some(h)) = (i == j, far.wall()) {
                let m = wall_factor(eta, h, (pos, radius), near, i, l)?;
                precondition(&m, l, b)?;
                continue;
            }
            // The correction seen from `j` to `i` (`j < i`): rows `(j, i, rot j, rot i)`.
            let c = pair_correction(eta, far, pos, radius, near, (j, i))?;
            pairs[p] = [j, i];
            match c {
                Some(c) => {
                    for (k, x) in l.iter_mut().enumerate() {
                        *x = T::m3_get(c[k / 36][(k % K) / 3], (k / K) % 3, k % 3);
                    }
                    factor_semidefinite(l, K)?;
                }
                // Coincident centres: no correction (as the dense path).
                None => l.fill(T::ZERO),
            }
            let m = pair_block(eta, far, pos, radius, near, [j, i]);
            precondition(&m, l, b)?;
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

    /// The entries found: close pairs and spheres near the wall.
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
