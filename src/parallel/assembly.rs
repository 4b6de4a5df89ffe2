//! The assembly of `mu_tt` in bands: each pair block evaluated on its own and stored
//! ([`assemble`]), or stored and applied at once ([`assemble_apply`]: the fused band
//! walks the rows in [`band`](super::band)'s order, so its product has the bits of a
//! product of the stored blocks). The first nested pair in band order is the error.

use super::{
    Pairs, Parallel, assemble_blocks, band_start, bands, blocked, by_bands, lanes, reduce,
};
use crate::fault::ParticleError;
use crate::linalg::{Block, tri};
use crate::real::Real;
use crate::rpy::{Hydro, pair_tt};

/// [`band`](super::band) while assembling: each block is evaluated, stored into `rows`
/// (the packed rows from `b0` on) and applied at once, in the same order, so the
/// product's bits are those of [`band`](super::band) on the stored blocks.
#[inline(always)]
pub(super) fn band_fused<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    rows: &mut [B],
    b0: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    src.start(rows, b0, x, y, z);
    for k in 0..y.len() {
        row_fused(src, rows, b0, k, x, y, z)?;
    }
    Ok(())
}

/// Row `b0 + k` of a [`band_fused`]: [`row`](super::row) on blocks evaluated and stored
/// on the way.
#[inline(always)]
fn row_fused<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    rows: &mut [B],
    b0: usize,
    k: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    let (base, i) = (tri(b0), b0 + k);
    let (level, eta, pos, radius) = (src.level, src.eta, src.pos, src.radius);
    let (pi, ai, xi) = (pos[i], radius[i], x[i]);
    #[inline(always)]
    fn pair<T: Real>(
        l: Hydro,
        eta: T,
        ai: T,
        aj: T,
        r: T::V3,
        i: usize,
        j: usize,
    ) -> Result<T::M3, ParticleError> {
        pair_tt(l, eta, ai, aj, r).ok_or(ParticleError::Nested { i: j, j: i })
    }
    let (left, inside) = rows[tri(i) - base..tri(i) - base + i].split_at_mut(b0);
    let mut acc = T::V3_ZERO;
    let others = left.iter_mut().zip(z.iter_mut()).zip(pos).zip(radius);
    for (j, (((o, zj), &pj), &aj)) in others.enumerate() {
        let b = pair::<T>(level, eta, ai, aj, pi - pj, i, j)?;
        *o = B::store(b);
        acc += b * x[j];
        *zj += T::m3_tmul(b, xi);
    }
    let (ys, yi) = y[..=k].split_at_mut(k);
    let others = inside.iter_mut().zip(ys).zip(&pos[b0..]).zip(&radius[b0..]);
    for (j, (((o, yj), &pj), &aj)) in others.enumerate() {
        let b = pair::<T>(level, eta, ai, aj, pi - pj, i, b0 + j)?;
        *o = B::store(b);
        acc += b * x[b0 + j];
        *yj += T::m3_tmul(b, xi);
    }
    yi[0] += acc;
    Ok(())
}

/// [`assemble_tt`](crate::mobility::assemble_tt) in bands through `par`: the same blocks
/// (each pair is evaluated on its own), the same first error.
pub fn assemble<T: Real>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [impl Block<T>],
) -> Result<(), ParticleError> {
    let src = Pairs::new(level, eta, pos, radius);
    let none = (&mut [][..], tri as fn(usize) -> usize);
    assemble_blocks(par, pos.len(), &src, out, none, |_, _, _, _| {})
}

/// [`assemble`] and [`product`](super::product) `y = mu_tt x` in one pass over the pairs
/// (each band computes its blocks, stores them and applies them at once): the same
/// blocks and the same bits as the two in turn, without reading the blocks back.
#[allow(clippy::too_many_arguments)]
pub fn assemble_apply<T: Real>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [impl Block<T>],
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    let n = pos.len();
    let out = &mut out[..tri(n)];
    let src = Pairs {
        level,
        eta,
        pos,
        radius,
    };
    if n < blocked::RUNS_MIN {
        // Pairs side by side where there are vector lanes to fill: not on 32-bit Arm
        // (the Cortex-M4F's FPU is scalar, and the lanes' arrays would cost its stack
        // ~3 kB), which keeps the row-by-row band and its instruction count.
        if level == Hydro::Rpy && n <= lanes::MAX && !cfg!(target_arch = "arm") {
            return lanes::band_lanes::<T, _>(src, out, x, &mut y[..n]);
        }
        return band_fused::<T, _>(src, out, 0, x, &mut y[..n], &mut []);
    }
    if bands(n) == 1 {
        return blocked::fused_rows::<T, _>(src, out, 0, x, &mut y[..n], &mut []);
    }
    by_bands::<T, _, _, _>(par, n, out, tri, y, z, |t, rows_t, yt, zt| {
        blocked::fused_rows::<T, _>(src, rows_t, band_start(n, t), x, yt, zt)
    })?;
    reduce::<T>(n, y, z, par);
    Ok(())
}
