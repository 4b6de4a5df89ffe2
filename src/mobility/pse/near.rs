//! The real-space half of PSE: the sparse near-field sum over pairs closer than the
//! cutoff, found with a cell list. Each block is the Ewald path's own real-space block
//! (`periodic::real::real_sum`: free RPY, either branch, minus the smooth `W` of the
//! split), so the two halves add to the same periodic RPY as the Ewald path.
//!
//! The product runs row by row (each row's neighbours in the cell list's fixed order),
//! evaluating each pair block once per row: twice the block evaluations of a
//! scatter-both-rows loop, but every row's sum is independent of every other row's, so
//! a threaded product splits rows and keeps the bits of one thread. The pair `(i, j)`
//! is always evaluated from the higher index (`r = r_hi - r_lo`) and transposed for the
//! other row, so the operator is exactly symmetric.

use super::{Pse, PseError};
use crate::fault::ParticleError;
use crate::mobility::periodic::PeriodicError;
use crate::mobility::periodic::real::real_sum;
use crate::mobility::periodic::{real_grand, real_self_rr};
use crate::real::Real;

/// The cell of a position (wrapped into the box), per axis.
#[inline(always)]
fn cell_of<T: Real>(pse: &Pse<T>, p: T::V3) -> [usize; 3] {
    let p = T::xyz(pse.cell.wrap_into(p));
    let l = pse.cell.size();
    let mut c = [0; 3];
    for d in 0..3 {
        let n = pse.cells[d];
        let v = libm::floor((p[d] / l[d]).to_f64() * n as f64);
        c[d] = (v.max(0.0) as usize).min(n - 1);
    }
    c
}

#[inline(always)]
fn linear(c: [usize; 3], n: [usize; 3]) -> usize {
    c[0] + n[0] * (c[1] + n[1] * c[2])
}

/// Sorts the spheres into cells (counting sort, index order within a cell):
/// `order[start[c]..start[c + 1]]` are the spheres of cell `c`.
pub(super) fn build<T: Real>(
    pse: &Pse<T>,
    pos: &[T::V3],
    order: &mut [usize],
    start: &mut [usize],
) {
    let nc = pse.cells;
    let total = nc[0] * nc[1] * nc[2];
    start[..=total].fill(0);
    for &p in pos {
        start[linear(cell_of(pse, p), nc) + 1] += 1;
    }
    for c in 0..total {
        start[c + 1] += start[c];
    }
    // Place with start[c] as the cursor, then shift the cursors back into starts.
    for (j, &p) in pos.iter().enumerate() {
        let c = linear(cell_of(pse, p), nc);
        order[start[c]] = j;
        start[c] += 1;
    }
    for c in (1..=total).rev() {
        start[c] = start[c - 1];
    }
    start[0] = 0;
}

/// The neighbouring cell indices along one axis: `c - 1, c, c + 1` (periodic) with
/// three cells or more, else every cell once.
#[inline(always)]
fn axis_neighbours(c: usize, n: usize) -> ([usize; 3], usize) {
    if n >= 3 {
        ([(c + n - 1) % n, c, (c + 1) % n], 3)
    } else {
        ([0, 1, 0], n)
    }
}

/// Calls `f(j, r0)` for every neighbour `j != i` of sphere `i` within the cutoff, in
/// the cell list's fixed order, `r0` the minimum-image separation `r_hi - r_lo` of the
/// pair's higher and lower index (the pair is always evaluated from the higher one, so
/// the operator is exactly symmetric); stops at the first error.
#[inline(always)]
fn for_each_neighbour<T: Real>(
    pse: &Pse<T>,
    pos: &[T::V3],
    (order, start): (&[usize], &[usize]),
    i: usize,
    mut f: impl FnMut(usize, T::V3) -> Result<(), PseError>,
) -> Result<(), PseError> {
    let rc2 = pse.split.r_cut * pse.split.r_cut;
    let nc = pse.cells;
    let c = cell_of(pse, pos[i]);
    let (nz, cz) = axis_neighbours(c[2], nc[2]);
    let (ny, cy) = axis_neighbours(c[1], nc[1]);
    let (nx, cx) = axis_neighbours(c[0], nc[0]);
    for &z in &nz[..cz] {
        for &y in &ny[..cy] {
            for &x in &nx[..cx] {
                let cell = linear([x, y, z], nc);
                for &j in &order[start[cell]..start[cell + 1]] {
                    if j == i {
                        continue;
                    }
                    let (hi, lo) = (i.max(j), i.min(j));
                    let r0 = pse.cell.minimum_image(pos[hi] - pos[lo]);
                    if !(T::norm2(r0) <= rc2) {
                        continue;
                    }
                    f(j, r0)?;
                }
            }
        }
    }
    Ok(())
}

/// A sphere inside another's image: `ParticleError::Nested { i: lower, j: higher }`.
fn nested(i: usize, j: usize) -> PseError {
    let (i, j) = (i.min(j), i.max(j));
    PseError::Periodic(PeriodicError::Particle(ParticleError::Nested { i, j }))
}

/// `rows[k] = sum_j M^real_ij F_j` for `i = order[first + k]`, over the pairs within the
/// cutoff and the self block. A sphere inside another's image is
/// `ParticleError::Nested { i: lower, j: higher }`.
#[allow(clippy::too_many_arguments)]
pub(super) fn product<T: Real>(
    pse: &Pse<T>,
    eta: T,
    (pos, radius): (&[T::V3], &[T]),
    force: &[T::V3],
    cells: (&[usize], &[usize]),
    first: usize,
    rows: &mut [T::V3],
) -> Result<(), PseError> {
    let split = &pse.split;
    // Rows in the cell list's order: neighbouring rows share their neighbours, so the
    // positions they read stay in cache. Each row's sum is its own: the order of rows
    // changes no bits.
    for (row, &i) in rows.iter_mut().zip(&cells.0[first..]) {
        let a = radius[i];
        // A sphere is never inside its own image (a < L/2): never `None`.
        let own = real_sum(split, eta, a, a, T::V3_ZERO, true).unwrap_or(T::M3_ZERO);
        let mut acc = own * force[i];
        for_each_neighbour(pse, pos, cells, i, |j, r0| {
            let (hi, lo) = (i.max(j), i.min(j));
            let b = real_sum(split, eta, radius[hi], radius[lo], r0, false)
                .ok_or_else(|| nested(i, j))?;
            acc += if i == hi {
                b * force[j]
            } else {
                T::m3_tmul(b, force[j])
            };
            Ok(())
        })?;
        *row = acc;
    }
    Ok(())
}

/// The grand product's near field: `rows[2k] = sum_j (tt_ij F_j + tr_ij T_j)` and
/// `rows[2k + 1] = sum_j (rt_ij F_j + rr_ij T_j)` of the real-space blocks (the Ewald
/// path's, [`real_grand`]) for `i = order[first + k]`, as [`product`] otherwise. The
/// self blocks: `tt` and `rr` (the `rt` self block vanishes); `tr_ij` is `rt_ji^T`.
#[allow(clippy::too_many_arguments)]
pub(super) fn product_grand<T: Real>(
    pse: &Pse<T>,
    eta: T,
    (pos, radius): (&[T::V3], &[T]),
    (force, torque): (&[T::V3], &[T::V3]),
    cells: (&[usize], &[usize]),
    first: usize,
    rows: &mut [T::V3],
) -> Result<(), PseError> {
    let split = &pse.split;
    for (row, &i) in rows.chunks_exact_mut(2).zip(&cells.0[first..]) {
        let a = radius[i];
        let own = real_sum(split, eta, a, a, T::V3_ZERO, true).unwrap_or(T::M3_ZERO);
        let (mut u, mut w) = (own * force[i], real_self_rr(split, eta, a) * torque[i]);
        for_each_neighbour(pse, pos, cells, i, |j, r0| {
            let (hi, lo) = (i.max(j), i.min(j));
            let b =
                real_grand(split, eta, radius[hi], radius[lo], r0).ok_or_else(|| nested(i, j))?;
            if i == hi {
                u += b.tt * force[j];
                u += T::m3_tmul(b.rt_ji, torque[j]);
                w += b.rt_ij * force[j];
                w += b.rr * torque[j];
            } else {
                u += T::m3_tmul(b.tt, force[j]);
                u += T::m3_tmul(b.rt_ij, torque[j]);
                w += b.rt_ji * force[j];
                w += T::m3_tmul(b.rr, torque[j]);
            }
            Ok(())
        })?;
        row[0] = u;
        row[1] = w;
    }
    Ok(())
}
