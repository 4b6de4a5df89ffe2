//! The mobility's `O(N^2)` work in bands of block rows, and the interface through which
//! a host runs the bands on several threads ([`Parallel`]).
//!
//! The kernel stays single-threaded: it cuts the assembly of `mu_tt` and the products
//! `y = mu_tt x` into independent jobs and hands them to the workspace's [`Parallel`]
//! ([`Workspace::with_parallel`](crate::Workspace::with_parallel); [`Serial`], one job
//! after the other, by default). A host implements [`Parallel`] with a thread pool (the
//! host crate `hydrorattle-parallel` does, with rayon).
//!
//! **Same bits on any number of threads.** The bands depend on the row count alone
//! ([`band_start`]): below [`BANDED_MIN`] rows there is one band and the arithmetic is
//! that of [`sym_matvec`](crate::linalg::sym_matvec); from there on [`BANDS`] bands of
//! equal area. A band's job writes its own rows of the product and, for the rows above
//! it, a partial sum of its transposed blocks into its own slice of scratch
//! ([`band_scratch`]); a second round of jobs adds those partial sums into each band's
//! rows in band order. Nothing depends on which thread runs a job or when.
//!
//! Products go through [`product`], assemblies through [`assemble`] and [`assemble_apply`]:
//! the one place where the stored mobility meets a vector (the integrators, the Krylov
//! metric).

mod blocked;
mod jobs;

pub(crate) use blocked::{assemble_apply_then, band_rows};
pub(crate) use jobs::{Packed, by_bands, by_bands_and, reduce};

use crate::error::ParticleError;
use crate::linalg::tri;
use crate::mobility::{Hydro, pair_tt, self_tt};
use crate::real::Real;

/// A way to run independent jobs, possibly at the same time.
pub trait Parallel: core::fmt::Debug {
    /// Runs every job exactly once, in any order or at once, and returns when all are
    /// done. The jobs share no mutable state, so any schedule gives the same result.
    fn run(&self, jobs: &mut [&mut (dyn FnMut() + Send)]);
}

/// One job after the other on the calling thread (the default, and firmware's).
#[derive(Clone, Copy, Debug, Default)]
pub struct Serial;

impl Parallel for Serial {
    fn run(&self, jobs: &mut [&mut (dyn FnMut() + Send)]) {
        for job in jobs.iter_mut() {
            job();
        }
    }
}

/// Row counts from which the mobility work is cut into [`BANDS`] bands (below: one).
pub const BANDED_MIN: usize = 512;

/// Bands of a banded mobility (a fixed count, so the bits do not depend on the threads).
pub const BANDS: usize = 16;

/// Bands for `n` block rows: 1 below [`BANDED_MIN`], else [`BANDS`].
pub const fn bands(n: usize) -> usize {
    if n < BANDED_MIN { 1 } else { BANDS }
}

/// First row of band `t` of `n` rows (`t = bands(n)` gives `n`): `n sqrt(t / bands)`
/// rounded down, so the bands hold about equal numbers of packed blocks.
pub const fn band_start(n: usize, t: usize) -> usize {
    let k = bands(n);
    if t >= k {
        return n;
    }
    // isqrt(n^2 t / k), exact in integers.
    let target = (n as u128) * (n as u128) * (t as u128) / (k as u128);
    let mut r = 0u128;
    let mut bit = 1u128 << 62;
    while bit > target {
        bit >>= 2;
    }
    let mut rem = target;
    while bit != 0 {
        if rem >= r + bit {
            rem -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    r as usize
}

/// Scratch vectors a banded product of `n` rows needs: band `t` keeps a partial sum for
/// the `band_start(n, t)` rows above it (0 with one band).
pub const fn band_scratch(n: usize) -> usize {
    let mut s = 0;
    let mut t = 1;
    while t < bands(n) {
        s += band_start(n, t);
        t += 1;
    }
    s
}

/// One band of the product: rows `b0..b0 + y.len()` of `y = A x` from the packed `a`,
/// with the transposed blocks left of the band summed into `z` (the `b0` rows above, from
/// zero), those inside it into `y`. Row `i` starts `y_i` from its diagonal term and adds
/// its lower blocks' products in order; the transposed products reach `y_j` from the rows
/// below in row order. With `b0 = 0` this is the one-pass
/// [`sym_matvec`](crate::linalg::sym_matvec).
#[inline(always)]
pub(crate) fn band<T: Real>(a: &[T::M3], b0: usize, x: &[T::V3], y: &mut [T::V3], z: &mut [T::V3]) {
    z.fill(T::V3_ZERO);
    for (k, yk) in y.iter_mut().enumerate() {
        let i = b0 + k;
        *yk = a[tri(i) + i] * x[i];
    }
    for k in 0..y.len() {
        row::<T>(a, b0, k, x, y, z);
    }
}

/// Row `b0 + k` of a [`band`]: its lower blocks' products summed in order into `y_k`,
/// their transposed products added to `z` (left of the band) and `y` (inside it).
#[inline(always)]
fn row<T: Real>(a: &[T::M3], b0: usize, k: usize, x: &[T::V3], y: &mut [T::V3], z: &mut [T::V3]) {
    let i = b0 + k;
    let (left, inside) = a[tri(i)..tri(i) + i].split_at(b0);
    let xi = x[i];
    let mut acc = T::V3_ZERO;
    for ((&b, zj), &xj) in left.iter().zip(z.iter_mut()).zip(x) {
        acc += b * xj;
        *zj += T::m3_tmul(b, xi);
    }
    let (ys, yi) = y[..=k].split_at_mut(k);
    for ((&b, yj), &xj) in inside.iter().zip(ys).zip(&x[b0..]) {
        acc += b * xj;
        *yj += T::m3_tmul(b, xi);
    }
    yi[0] += acc;
}

/// The pairs a fused band evaluates its blocks from.
#[derive(Clone, Copy)]
struct Pairs<'a, T: Real> {
    level: Hydro,
    eta: T,
    pos: &'a [T::V3],
    radius: &'a [T],
}

impl<T: Real> Pairs<'_, T> {
    /// The diagonal blocks of rows `b0..b0 + y.len()` into `rows` (the packed rows from
    /// `b0` on), `y` started from their products, `z` zeroed: a fused band's first step.
    #[inline(always)]
    fn start(&self, rows: &mut [T::M3], b0: usize, x: &[T::V3], y: &mut [T::V3], z: &mut [T::V3]) {
        let base = tri(b0);
        z.fill(T::V3_ZERO);
        for (k, yk) in y.iter_mut().enumerate() {
            let i = b0 + k;
            let diag = T::m3_diag(self_tt(self.eta, self.radius[i]));
            rows[tri(i) - base + i] = diag;
            *yk = diag * x[i];
        }
    }
}

/// [`band`] while assembling: each block is evaluated, stored into `rows` (the packed
/// rows from `b0` on) and applied at once, in the same order, so the product's bits are
/// those of [`band`] on the stored blocks.
#[inline(always)]
fn band_fused<T: Real>(
    src: Pairs<'_, T>,
    rows: &mut [T::M3],
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

/// Row `b0 + k` of a [`band_fused`]: [`row`] on blocks evaluated and stored on the way.
#[inline(always)]
fn row_fused<T: Real>(
    src: Pairs<'_, T>,
    rows: &mut [T::M3],
    b0: usize,
    k: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    let (base, i) = (tri(b0), b0 + k);
    let row = &mut rows[tri(i) - base..tri(i) - base + i];
    row_each(src, b0, k, x, y, z, |j, b| row[j] = b)
}

/// [`row`] on blocks evaluated on the way, each handed to `keep(j, block)`.
#[inline(always)]
fn row_each<T: Real>(
    src: Pairs<'_, T>,
    b0: usize,
    k: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
    mut keep: impl FnMut(usize, T::M3),
) -> Result<(), ParticleError> {
    let i = b0 + k;
    let (level, eta, pos, radius) = (src.level, src.eta, src.pos, src.radius);
    let (pi, ai, xi) = (pos[i], radius[i], x[i]);
    let pair = |j: usize| {
        pair_tt(level, eta, ai, radius[j], pi - pos[j]).ok_or(ParticleError::Nested { i: j, j: i })
    };
    let mut acc = T::V3_ZERO;
    for (j, zj) in z[..b0].iter_mut().enumerate() {
        let b = pair(j)?;
        keep(j, b);
        acc += b * x[j];
        *zj += T::m3_tmul(b, xi);
    }
    let (ys, yi) = y[..=k].split_at_mut(k);
    for (j, yj) in (b0..).zip(ys) {
        let b = pair(j)?;
        keep(j, b);
        acc += b * x[j];
        *yj += T::m3_tmul(b, xi);
    }
    yi[0] += acc;
    Ok(())
}

/// `y = mu_tt x` without storing `mu_tt`, in the bands of [`product`] through `par`
/// (`z` holds at least [`band_scratch`]`(n)` vectors): each band evaluates its rows'
/// blocks and applies them at once, so the bits are those of [`assemble`] followed by
/// [`product`] (and below [`BANDED_MIN`] rows those of
/// [`mobility::tt_product`](crate::mobility::tt_product)) on any number of threads, in
/// `O(N)` memory. Each pair is evaluated once.
#[allow(clippy::too_many_arguments)]
pub fn product_free<T: Real>(
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
    let band = |b0: usize, yt: &mut [T::V3], zt: &mut [T::V3]| {
        zt.fill(T::V3_ZERO);
        for (k, yk) in yt.iter_mut().enumerate() {
            *yk = T::m3_diag(self_tt(eta, radius[b0 + k])) * x[b0 + k];
        }
        (0..yt.len()).try_for_each(|k| row_each(src, b0, k, x, yt, zt, |_, _| {}))
    };
    if bands(n) == 1 {
        return band(0, &mut y[..n], &mut []);
    }
    by_bands::<T, _, _>(par, n, &mut [], tri, y, z, |t, _, yt, zt| {
        band(band_start(n, t), yt, zt)
    })?;
    reduce::<T>(n, y, z, par);
    Ok(())
}

/// `y = A x` for the packed symmetric `A` of `n` block rows, in bands through `par`;
/// `z` holds at least [`band_scratch`]`(n)` vectors. Bit-identical to
/// [`sym_matvec`](crate::linalg::sym_matvec) below [`BANDED_MIN`] rows; from there on the
/// same bits on any number of threads.
pub fn product<T: Real>(
    par: &dyn Parallel,
    a: &[T::M3],
    n: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    if bands(n) == 1 {
        band::<T>(a, 0, x, &mut y[..n], &mut []);
        return;
    }
    let _ = by_bands::<T, (), _>(par, n, &mut [], tri, y, z, |t, _, yt, zt| {
        band_rows::<T>(a, band_start(n, t), x, yt, zt);
        Ok(())
    });
    reduce::<T>(n, y, z, par);
}

/// [`assemble_tt`](crate::mobility::assemble_tt) in bands through `par`: the same blocks
/// (each pair is evaluated on its own), the same first error.
pub fn assemble<T: Real>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), ParticleError> {
    let n = pos.len();
    let out = &mut out[..tri(n)];
    if bands(n) == 1 {
        return rows::<T>(level, eta, pos, radius, 0..n, out);
    }
    by_bands::<T, _, _>(par, n, out, tri, &mut [], &mut [], |t, rows_t, _, _| {
        let (b0, b1) = (band_start(n, t), band_start(n, t + 1));
        rows::<T>(level, eta, pos, radius, b0..b1, rows_t)
    })
}

/// Packed rows `range` of `mu_tt` into `out` (which starts at row `range.start`).
fn rows<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    range: core::ops::Range<usize>,
    out: &mut [T::M3],
) -> Result<(), ParticleError> {
    let base = tri(range.start);
    for i in range {
        let (pairs, diag) = out[tri(i) - base..=tri(i) - base + i].split_at_mut(i);
        for (j, o) in pairs.iter_mut().enumerate() {
            *o = pair_tt(level, eta, radius[i], radius[j], pos[i] - pos[j])
                .ok_or(ParticleError::Nested { i: j, j: i })?;
        }
        diag[0] = T::m3_diag(self_tt(eta, radius[i]));
    }
    Ok(())
}

/// [`assemble`] and [`product`] `y = mu_tt x` in one pass over the pairs (each band
/// computes its blocks, stores them and applies them at once): the same blocks and the
/// same bits as the two in turn, without reading the blocks back.
#[allow(clippy::too_many_arguments)]
pub fn assemble_apply<T: Real>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
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
        return band_fused::<T>(src, out, 0, x, &mut y[..n], &mut []);
    }
    if bands(n) == 1 {
        return blocked::fused_rows::<T>(src, out, 0, x, &mut y[..n], &mut []);
    }
    by_bands::<T, _, _>(par, n, out, tri, y, z, |t, rows_t, yt, zt| {
        blocked::fused_rows::<T>(src, rows_t, band_start(n, t), x, yt, zt)
    })?;
    reduce::<T>(n, y, z, par);
    Ok(())
}
