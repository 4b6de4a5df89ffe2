//! The recompute path: `y = mu_tt x` in the bands of [`product`](super::product), each
//! pair block evaluated where it is used and never stored (the matrix-free product,
//! compute-bound: no `O(N^2)` stream from memory, so it scales with the cores).
//!
//! Each band walks its rows as [`fused_rows`](super::blocked) does, the blocks going
//! into a small buffer on the stack instead of the packed mobility: the same blocks, in
//! the same order for every entry of the result, so the bits of the stored banded
//! product ([`product`](super::product) after [`assemble`](super::assemble)) on any
//! number of threads.

use super::blocked::runs_k;
use super::{Pairs, Parallel, band_start, by_bands_then_reduce};
use crate::fault::ParticleError;
use crate::real::Real;
use crate::rpy::{Hydro, self_tt};

/// Columns evaluated into the stack buffer at a time (whole runs of square roots).
const SPAN: usize = 64;

/// Rows `b0..b0 + y_q.len()` of `y_q = mu_tt x_q` for `K` vectors, their transposed
/// blocks left of the band summed into `z_q` (from zero), as a stored band computes
/// them: each block evaluated once and applied to every vector.
#[inline(always)]
fn band_free<T: Real, const K: usize>(
    src: Pairs<'_, T>,
    b0: usize,
    x: [&[T::V3]; K],
    mut y: [&mut [T::V3]; K],
    mut z: [&mut [T::V3]; K],
) -> Result<(), ParticleError> {
    let m = y[0].len();
    for q in 0..K {
        z[q].fill(T::V3_ZERO);
        for k in 0..m {
            let i = b0 + k;
            y[q][k] = T::m3_diag(self_tt(src.eta, src.radius[i])) * x[q][i];
        }
    }
    if src.level == Hydro::FreeDraining {
        // No pair term: every pair block is zero, and the sums below would add `+0` to
        // each row (which turns a `-0` into `+0`, nothing else). Nested spheres are the
        // step's start and acceptance checks' to refuse (through the cell list).
        for yq in y.iter_mut() {
            for v in yq.iter_mut() {
                *v += T::V3_ZERO;
            }
        }
        return Ok(());
    }
    let mut buf = [T::M3_ZERO; SPAN];
    for k in 0..m {
        let i = b0 + k;
        let mut acc = [T::V3_ZERO; K];
        // Left of the band: columns 0..b0 into z; inside it: b0..i into y.
        for j0 in (0..b0).step_by(SPAN) {
            let j1 = (j0 + SPAN).min(b0);
            let blocks = &mut buf[..j1 - j0];
            let outs = z.each_mut().map(|zq| &mut zq[j0..j1]);
            runs_k(src, i, j0, blocks, outs, x.map(|xq| &xq[j0..]), &mut acc)?;
        }
        for j0 in (b0..i).step_by(SPAN) {
            let j1 = (j0 + SPAN).min(i);
            let blocks = &mut buf[..j1 - j0];
            let outs = y.each_mut().map(|yq| &mut yq[j0 - b0..j1 - b0]);
            runs_k(src, i, j0, blocks, outs, x.map(|xq| &xq[j0..]), &mut acc)?;
        }
        for q in 0..K {
            y[q][k] += acc[q];
        }
    }
    Ok(())
}

/// `y = mu_tt x` at `pos` without storing `mu_tt`, in bands through `par` (`z`: at least
/// [`band_scratch`](super::band_scratch)`(n)` vectors): the bits of [`assemble`](super::assemble)
/// then [`product`](super::product) at every `n` and on any number of threads, one pair
/// evaluation per block. Nested spheres are the error the assembly gives.
#[allow(clippy::too_many_arguments)]
pub fn free_product<T: Real>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    free_products::<T, 1>(par, level, eta, pos, radius, [x], [y], z)
}

/// [`free_product`] of `K` vectors in one pass over the pairs (each block evaluated
/// once, applied to all `K`): `y[q]` gets the bits `free_product` gives it for `x[q]`.
/// `z` holds at least `K` [`band_scratch`](super::band_scratch)`(n)` vectors.
#[allow(clippy::too_many_arguments)]
pub fn free_products<T: Real, const K: usize>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    x: [&[T::V3]; K],
    y: [&mut [T::V3]; K],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    let n = pos.len();
    by_bands_then_reduce::<T, _, K>(par, n, y, z, |t, yt, zt| {
        free_band::<T, K>((level, eta, pos, radius), t, x, yt, zt)
    })
}

/// Band `t` of [`free_products`] (as [`super::product_band`] is of
/// [`super::products`]; inlined, for a host's wider-vector copy).
#[inline(always)]
pub fn free_band<T: Real, const K: usize>(
    (level, eta, pos, radius): (Hydro, T, &[T::V3], &[T]),
    t: usize,
    x: [&[T::V3]; K],
    y: [&mut [T::V3]; K],
    z: [&mut [T::V3]; K],
) -> Result<(), ParticleError> {
    let src = Pairs {
        level,
        eta,
        pos,
        radius,
    };
    band_free::<T, K>(src, band_start(pos.len(), t), x, y, z)
}
