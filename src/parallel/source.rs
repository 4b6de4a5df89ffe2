//! The band loops every geometry's mobility shares, written once over a source of
//! blocks ([`Blocks`]): the packed rows of an assembly ([`assemble_blocks`]) and the
//! matrix-free product in the bands of the stored one ([`product_blocks`],
//! [`band_blocks`]). A geometry gives its self block, its pair block `(i, j)`, `j < i`,
//! and what a row needs of a sphere once (a wall lifts a sphere that comes too close);
//! the loops give the order, and with it the bits, of the stored banded product on any
//! number of threads.

use super::{Packed, Parallel, band_start, bands, by_bands_and, by_bands_then_reduce};
use crate::fault::ParticleError;
use crate::linalg::{Block, tri};
use crate::real::Real;
use crate::rpy::{pair_tt, self_tt};

/// A geometry's `mu_tt` as the band loops read it, block by block.
pub(crate) trait Blocks<T: Real>: Sync {
    /// What the blocks of a row or column read of its sphere, found once.
    type Site: Copy;
    /// A sphere the geometry cannot take, or a nested pair.
    type Error: Send;
    /// Sphere `i` as the blocks read it (an error where the geometry refuses it).
    fn site(&self, i: usize) -> Result<Self::Site, Self::Error>;
    /// The self block of sphere `i`.
    fn diag(&self, i: usize, si: Self::Site) -> T::M3;
    /// The block `(i, j)`, `j < i` (not symmetric in general, as above a wall).
    fn pair(
        &self,
        i: usize,
        si: Self::Site,
        j: usize,
        sj: Self::Site,
    ) -> Result<T::M3, Self::Error>;
}

/// Packed rows `range` of `mu_tt` into `out` (which starts at row `range.start`): each
/// row's pairs in column order, then its self block; each row handed to
/// `row_done(i, blocks)` once written. The first error in row order.
#[inline(always)]
pub(crate) fn rows<T: Real, B: Block<T>, S: Blocks<T>>(
    src: &S,
    range: core::ops::Range<usize>,
    out: &mut [B],
    mut row_done: impl FnMut(usize, &[B]),
) -> Result<(), S::Error> {
    let base = tri(range.start);
    for i in range {
        let si = src.site(i)?;
        let row = tri(i) - base;
        let (pairs, diag) = out[row..=row + i].split_at_mut(i);
        for (j, o) in pairs.iter_mut().enumerate() {
            *o = B::store(src.pair(i, si, j, src.site(j)?)?);
        }
        diag[0] = B::store(src.diag(i, si));
        row_done(i, &out[row..=row + i]);
    }
    Ok(())
}

/// The `n x n` packed `mu_tt` of `src` into `out` ([`tri`]`(n)` blocks), in bands
/// through `par`, handing each row `i`, just written and still in the core's cache, to
/// `then(i, i + 1, row, side_rows)` with `side` from its row `i` on (empty where `side`
/// is): the same blocks and the same first error on any number of threads.
pub(crate) fn assemble_blocks<T: Real, B: Block<T>, S: Blocks<T>, F>(
    par: &dyn Parallel,
    n: usize,
    src: &S,
    out: &mut [B],
    side: Packed<'_, T::M3>,
    then: F,
) -> Result<(), S::Error>
where
    F: Fn(usize, usize, &[B], &mut [T::M3]) + Sync,
{
    let out = &mut out[..tri(n)];
    if bands(n) == 1 && side.0.is_empty() {
        return rows(src, 0..n, out, |_, _| {});
    }
    let side_start = side.1;
    let job = |t, rows_t: &mut [B], st: &mut [T::M3], _: &mut [T::V3], _: &mut [T::V3]| {
        let (b0, b1) = (band_start(n, t), band_start(n, t + 1));
        let first = side_start(b0);
        rows(src, b0..b1, rows_t, |i, row| {
            let rest = st.get_mut(side_start(i) - first..).unwrap_or_default();
            then(i, i + 1, row, rest);
        })
    };
    let out = (out, tri as fn(usize) -> usize);
    by_bands_and::<T, _, _, _, _>(par, n, out, side, &mut [], &mut [], job)
}

/// Every sphere's site, in order: the first sphere the geometry refuses.
#[inline(always)]
pub(crate) fn check_sites<T: Real, S: Blocks<T>>(src: &S, n: usize) -> Result<(), S::Error> {
    (0..n).try_for_each(|i| src.site(i).map(|_| ()))
}

/// The self block and the pair block of `src` as [`band_blocks`] reads them, every
/// site checked ([`check_sites`]) before.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn checked<'a, T: Real, S: Blocks<T>>(
    src: &'a S,
) -> (
    impl Fn(usize) -> T::M3 + 'a,
    impl Fn(usize, usize) -> Result<T::M3, S::Error> + 'a,
) {
    let diag = |i: usize| match src.site(i) {
        Ok(si) => src.diag(i, si),
        Err(_) => T::M3_ZERO, // Not reached: the sites were checked.
    };
    let pair = |i: usize, j: usize| src.pair(i, src.site(i)?, j, src.site(j)?);
    (diag, pair)
}

/// `y = mu_tt x` of `src` without storing it, in the bands of
/// [`product`](super::product) through `par` (`z`: at least
/// [`band_scratch`](super::band_scratch)`(n)` vectors): the bits of an assembly then the
/// stored banded product at every `n` and on any number of threads. The first sphere
/// the geometry refuses, then the first nested pair in row order.
pub(crate) fn product_blocks<T: Real, S: Blocks<T>>(
    par: &dyn Parallel,
    src: &S,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), S::Error> {
    let n = x.len();
    check_sites(src, n)?;
    by_bands_then_reduce::<T, _, 1>(par, n, [y], z, |t, [yt], [zt]| {
        let (diag, pair) = checked(src);
        band_blocks::<T, _>(band_start(n, t), diag, pair, x, yt, zt)
    })
}

/// [`product_blocks`] in one band on the calling thread: the order of an assembly
/// followed by [`sym_matvec`](crate::linalg::sym_matvec).
pub(crate) fn serial_product<T: Real, S: Blocks<T>>(
    src: &S,
    x: &[T::V3],
    y: &mut [T::V3],
) -> Result<(), S::Error> {
    let n = x.len();
    check_sites(src, n)?;
    let (diag, pair) = checked(src);
    band_blocks::<T, _>(0, diag, pair, x, &mut y[..n], &mut [])
}

/// Rows `b0..b0 + y.len()` of `y = A x` for a general block source: `diag(i)` the
/// diagonal block, `block(i, j)` (`j < i`) the lower block (not symmetric in general,
/// as above a wall), evaluated where they are used, summed as the stored row-by-row
/// band [`band`](super::band) sums the stored blocks (the same bits on any number of
/// threads). The first error in row order.
#[inline(always)]
pub(crate) fn band_blocks<T: Real, E>(
    b0: usize,
    diag: impl Fn(usize) -> T::M3,
    block: impl Fn(usize, usize) -> Result<T::M3, E>,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), E> {
    z.fill(T::V3_ZERO);
    for (k, yk) in y.iter_mut().enumerate() {
        *yk = diag(b0 + k) * x[b0 + k];
    }
    for k in 0..y.len() {
        let i = b0 + k;
        let (xi, mut acc) = (x[i], T::V3_ZERO);
        for (j, zj) in z.iter_mut().enumerate() {
            let b = block(i, j)?;
            acc += b * x[j];
            *zj += T::m3_tmul(b, xi);
        }
        let (ys, yi) = y[..=k].split_at_mut(k);
        for (c, yj) in ys.iter_mut().enumerate() {
            let b = block(i, b0 + c)?;
            acc += b * x[b0 + c];
            *yj += T::m3_tmul(b, xi);
        }
        yi[0] += acc;
    }
    Ok(())
}

/// Block `(p, q)` of `mu_tt` of `src`, evaluated from the higher index as the packed
/// rows store it; transposed when `p < q` where the blocks are not symmetric
/// (`general`, as above a wall).
#[inline(always)]
pub(crate) fn block_at<T: Real, S: Blocks<T>>(
    src: &S,
    general: bool,
    p: usize,
    q: usize,
) -> Result<T::M3, S::Error> {
    let (i, j) = if p >= q { (p, q) } else { (q, p) };
    let si = src.site(i)?;
    if i == j {
        return Ok(src.diag(i, si));
    }
    let b = src.pair(i, si, j, src.site(j)?)?;
    Ok(if general && p < q { T::transpose(b) } else { b })
}

/// Free space: the RPY (or Oseen, or free-draining) blocks of `crate::rpy`.
impl<T: Real> Blocks<T> for super::Pairs<'_, T> {
    type Site = ();
    type Error = ParticleError;
    #[inline(always)]
    fn site(&self, _: usize) -> Result<(), ParticleError> {
        Ok(())
    }
    #[inline(always)]
    fn diag(&self, i: usize, _: ()) -> T::M3 {
        T::m3_diag(self_tt(self.eta, self.radius[i]))
    }
    #[inline(always)]
    fn pair(&self, i: usize, _: (), j: usize, _: ()) -> Result<T::M3, ParticleError> {
        let (pos, radius) = (self.pos, self.radius);
        pair_tt(self.level, self.eta, radius[i], radius[j], pos[i] - pos[j])
            .ok_or(ParticleError::Nested { i: j, j: i })
    }
}
