//! The recompute path: `y = mu_tt x` in the bands of [`product`](super::product), each
//! pair block evaluated where it is used and never stored (the matrix-free product,
//! compute-bound: no `O(N^2)` stream from memory, so it scales with the cores).
//!
//! Each band walks its rows as [`fused_rows`](super::blocked) does, the blocks going
//! into a small buffer on the stack instead of the packed mobility: the same blocks, in
//! the same order for every entry of the result, so the bits of the stored banded
//! product ([`product`](super::product) after [`assemble`](super::assemble)) on any
//! number of threads.

use super::blocked::runs;
use super::{Pairs, Parallel, band_start, bands, by_bands, reduce};
use crate::error::ParticleError;
use crate::linalg::tri;
use crate::mobility::{Hydro, self_tt};
use crate::real::Real;

/// Columns evaluated into the stack buffer at a time (whole runs of square roots).
const SPAN: usize = 64;

/// Rows `b0..b0 + y.len()` of `y = mu_tt x`, their transposed blocks left of the band
/// summed into `z` (from zero), as a stored band computes them.
fn band_free<T: Real>(
    src: Pairs<'_, T>,
    b0: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    z.fill(T::V3_ZERO);
    for (k, yk) in y.iter_mut().enumerate() {
        let i = b0 + k;
        *yk = T::m3_diag(self_tt(src.eta, src.radius[i])) * x[i];
    }
    let mut buf = [T::M3_ZERO; SPAN];
    for k in 0..y.len() {
        let i = b0 + k;
        let mut acc = T::V3_ZERO;
        // Left of the band: columns 0..b0 into z; inside it: b0..i into y.
        for j0 in (0..b0).step_by(SPAN) {
            let j1 = (j0 + SPAN).min(b0);
            let blocks = &mut buf[..j1 - j0];
            runs(src, i, j0, blocks, &mut z[j0..j1], &x[j0..], &mut acc)?;
        }
        let (ys, yi) = y[..=k].split_at_mut(k);
        for j0 in (b0..i).step_by(SPAN) {
            let j1 = (j0 + SPAN).min(i);
            let blocks = &mut buf[..j1 - j0];
            runs(
                src,
                i,
                j0,
                blocks,
                &mut ys[j0 - b0..j1 - b0],
                &x[j0..],
                &mut acc,
            )?;
        }
        yi[0] += acc;
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
    let n = pos.len();
    let src = Pairs {
        level,
        eta,
        pos,
        radius,
    };
    if bands(n) == 1 {
        return band_free::<T>(src, 0, x, &mut y[..n], &mut []);
    }
    by_bands::<T, _, _>(par, n, &mut [], tri, y, z, |t, _, yt, zt| {
        band_free::<T>(src, band_start(n, t), x, yt, zt)
    })?;
    reduce::<T>(n, y, z, par);
    Ok(())
}
