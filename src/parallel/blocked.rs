//! The banded product walking [`ROWS`] block rows at once, and the fused assembly taking
//! its square roots in runs of [`RUN`] pairs: the same arithmetic, in the same order for
//! every entry of the result, as the row-by-row [`band`](super::band) and
//! [`band_fused`](super::assembly::band_fused), so the same bits. The product is used
//! from [`BANDED_MIN`](super::BANDED_MIN) rows on, where the packed mobility no longer
//! fits in cache; the runs from [`RUNS_MIN`] beads on.
//!
//! Why: out of cache the row-by-row product waits on one stream of blocks at a time
//! (N = 1024, 38 MB: 6.2 ns per block against 2.9 ns in cache). Walking [`ROWS`] rows
//! column by column reads [`ROWS`] streams at once, and each `x_j` and each partial sum
//! `y_j` (or `z_j`) is loaded and stored once per [`ROWS`] blocks instead of once per
//! block: 4.0 ns per block at N = 1024 (see docs/BENCHMARKS.md).
//!
//! Entry by entry nothing moves: row `i`'s own sum `acc_i` still adds its blocks in
//! column order, and `y_j` still receives the transposed products of the rows below it
//! in row order (row `i`, then `i + 1`, ...), because a column visits the rows of a
//! group in order.

use super::{Packed, Pairs, Parallel, band_start, bands, by_bands_and, reduce};
use crate::fault::ParticleError;
use crate::linalg::{Block, tri};
use crate::real::Real;
use crate::rpy::{Hydro, pair_norm2, pair_tt_from};

/// Block rows walked together: 8 measured best at N = 1024 and 2048 (4: 4.7, 8: 4.0,
/// 12: 4.3, 16: 5.3 ns per block at N = 1024).
pub(super) const ROWS: usize = 8;

/// Column `j` for a group of rows and `K` vectors: `acc_rq += B_rj x_qj` for every row
/// `r` of the group, then `out_q += B_rj^T x_qr` in row order, for each vector `q` (each
/// sum in the order of one vector's product: the vectors only share the block's load).
#[inline(always)]
fn column<T: Real, B: Block<T>, const R: usize, const K: usize>(
    rows: &[&[B]; R],
    j: usize,
    xj: [T::V3; K],
    xs: &[[T::V3; K]; R],
    acc: &mut [[T::V3; K]; R],
    out: [&mut T::V3; K],
) {
    let mut o: [T::V3; K] = core::array::from_fn(|q| *out[q]);
    for r in 0..R {
        let b = rows[r][j];
        for q in 0..K {
            acc[r][q] += b.mul(xj[q]);
            o[q] += b.tmul(xs[r][q]);
        }
    }
    for (dst, v) in out.into_iter().zip(o) {
        *dst = v;
    }
}

/// Rows `b0..b0 + y_q.len()` of `y_q = A x_q` for `K` vectors in one pass over the
/// blocks (a block product), [`ROWS`] rows at a time, the rows left over at the band's
/// end one by one: output `q` gets the bits [`band`](super::band) gives it alone.
#[inline(always)]
pub(crate) fn band_rows_k<T: Real, B: Block<T>, const K: usize>(
    a: &[B],
    b0: usize,
    x: [&[T::V3]; K],
    mut y: [&mut [T::V3]; K],
    mut z: [&mut [T::V3]; K],
) {
    for zq in z.iter_mut() {
        zq.fill(T::V3_ZERO);
    }
    let m = y[0].len();
    for k in 0..m {
        let i = b0 + k;
        for q in 0..K {
            y[q][k] = a[tri(i) + i].mul(x[q][i]);
        }
    }
    // Rows a group walks: `ROWS` for one vector, `ROWS / 2` for two, one row from four
    // on, so that the group's running sums (`3 R K` scalars) stay about the size that
    // measured best for one vector; any group size gives the same bits. (k = 4 with 8
    // rows spilled: 0.71 of four single products' time at N = 1024; with one row, 0.77
    // to 0.93 in CPU time, docs/BENCHMARKS.md.)
    match K {
        1 => groups::<T, B, ROWS, K>(a, b0, x, &mut y, &mut z),
        2 => groups::<T, B, { ROWS / 2 }, K>(a, b0, x, &mut y, &mut z),
        _ => groups::<T, B, 1, K>(a, b0, x, &mut y, &mut z),
    }
}

/// The rows of a [`band_rows_k`] in groups of `R`, the rows left over one by one.
#[inline(always)]
fn groups<T: Real, B: Block<T>, const R: usize, const K: usize>(
    a: &[B],
    b0: usize,
    x: [&[T::V3]; K],
    y: &mut [&mut [T::V3]; K],
    z: &mut [&mut [T::V3]; K],
) {
    let m = y[0].len();
    let mut k = 0;
    while k + R <= m {
        group::<T, B, R, K>(a, b0, k, x, y, z);
        k += R;
    }
    for k in k..m {
        group::<T, B, 1, K>(a, b0, k, x, y, z);
    }
}

/// Rows `b0 + k..b0 + k + R` of a [`band_rows_k`], walked column by column.
#[inline(always)]
fn group<T: Real, B: Block<T>, const R: usize, const K: usize>(
    a: &[B],
    b0: usize,
    k: usize,
    x: [&[T::V3]; K],
    y: &mut [&mut [T::V3]; K],
    z: &mut [&mut [T::V3]; K],
) {
    let i = b0 + k;
    let rows: [&[B]; R] = core::array::from_fn(|r| &a[tri(i + r)..=tri(i + r) + i + r]);
    let xs: [[T::V3; K]; R] = core::array::from_fn(|r| x.map(|xq| xq[i + r]));
    let mut acc = [[T::V3_ZERO; K]; R];
    for j in 0..b0 {
        let out = z.each_mut().map(|zq| &mut zq[j]);
        column::<T, B, R, K>(&rows, j, x.map(|xq| xq[j]), &xs, &mut acc, out);
    }
    for c in 0..k {
        let out = y.each_mut().map(|yq| &mut yq[c]);
        column::<T, B, R, K>(&rows, b0 + c, x.map(|xq| xq[b0 + c]), &xs, &mut acc, out);
    }
    // The group's own triangle, row by row: row `i + r` meets columns `i..i + r`,
    // whose sums are complete before it adds to them.
    for (r, (xr, acc_r)) in xs.iter().zip(&mut acc).enumerate() {
        for c in 0..r {
            let b = rows[r][i + c];
            for q in 0..K {
                acc_r[q] += b.mul(x[q][i + c]);
                y[q][k + c] += b.tmul(xr[q]);
            }
        }
        for q in 0..K {
            y[q][k + r] += acc_r[q];
        }
    }
}

/// Beads from which the fused assembly takes its square roots in runs ([`fused_rows`];
/// 14.0 -> 10.7 ns per block from N = 64 to 256). Below, the row-by-row
/// [`band_fused`](super::assembly::band_fused): the firmware's N = 25 keeps its code and
/// instruction count.
pub(super) const RUNS_MIN: usize = 64;

/// Columns a fused row evaluates together: their square roots and divisions first, then
/// their blocks (see [`pair_norm2`]).
const RUN: usize = 8;

/// [`band_fused`](super::assembly::band_fused) with the same blocks and bits, each row
/// taking the square roots of [`RUN`] pairs before building their blocks. The assembly
/// is bound by those roots' latency, not by memory, so rows are taken one at a time
/// (walking [`ROWS`] at once did not pay here: 15.0 -> 16.3 ns per block at N = 1024).
#[inline(always)]
pub(super) fn fused_rows<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    out: &mut [B],
    b0: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    fused_rows_then(src, out, b0, x, y, z, |_, _| {})
}

/// [`fused_rows`], handing each row's blocks (`0 ..= i`) to `row_done(i, blocks)` as
/// soon as they are written, while they are still in the core's cache (a band of a
/// large mobility is not: 38 MB at N = 4096).
#[inline(always)]
fn fused_rows_then<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    out: &mut [B],
    b0: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
    mut row_done: impl FnMut(usize, &[B]),
) -> Result<(), ParticleError> {
    src.start(out, b0, x, y, z);
    let base = tri(b0);
    for k in 0..y.len() {
        let i = b0 + k;
        let (left, inside) = out[tri(i) - base..tri(i) - base + i].split_at_mut(b0);
        let mut acc = T::V3_ZERO;
        runs(src, i, 0, left, z, x, &mut acc)?;
        let (ys, yi) = y[..=k].split_at_mut(k);
        runs(src, i, b0, inside, ys, &x[b0..], &mut acc)?;
        yi[0] += acc;
        row_done(i, &out[tri(i) - base..=tri(i) - base + i]);
    }
    Ok(())
}

/// [`assemble_apply`](super::assemble_apply), handing each row `i` of the mobility,
/// just written and still in cache, to `then(i, i + 1, row, side_rows)` with `side`
/// from its row `i` on (in one band of rows `0..n` below
/// [`BANDED_MIN`](super::BANDED_MIN)): a second use of the blocks without a second pass
/// over memory (the reduced copy of the Lanczos noise and of
/// [`Params::compact_products`](crate::Params::compact_products)). Row by row, not band
/// by band: a band of a large mobility (38 MB at N = 4096) is out of cache by its end,
/// and packing it afterwards read it back from memory. The same blocks and product bits either way.
/// (`assemble_apply` itself does not go through here: as a generic over `then` it
/// cost the Brownian firmware 3.7 kB of flash.)
#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble_apply_then<T: Real, B: Block<T>, F>(
    par: &dyn Parallel,
    (level, eta, pos, radius): (Hydro, T, &[T::V3], &[T]),
    out: &mut [B],
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
    (side, side_start): Packed<'_, T::M3>,
    then: F,
) -> Result<(), ParticleError>
where
    F: Fn(usize, usize, &[B], &mut [T::M3]) + Sync,
{
    let n = pos.len();
    let out = &mut out[..tri(n)];
    if bands(n) == 1 {
        super::assemble_apply(par, level, eta, pos, radius, out, x, y, z)?;
        then(0, n, out, side);
        return Ok(());
    }
    let src = Pairs {
        level,
        eta,
        pos,
        radius,
    };
    let bands = (out, tri as fn(usize) -> usize);
    by_bands_and::<T, _, _, _, _>(
        par,
        n,
        bands,
        (side, side_start),
        y,
        z,
        |t, rows, st, yt, zt| {
            // Each row goes to `then` as soon as it is written (still in cache).
            let b0 = band_start(n, t);
            let first = side_start(b0);
            fused_rows_then::<T, B>(src, rows, b0, x, yt, zt, |i, row| {
                then(i, i + 1, row, &mut st[side_start(i) - first..]);
            })
        },
    )?;
    reduce::<T>(n, y, z, par);
    Ok(())
}

/// Row `i`'s blocks for the columns from `j0` into `blocks`, their products with `x`
/// (which starts at column `j0`) summed into `acc` in column order, their transposed
/// products with `x_i` added to `outs`.
#[inline(always)]
pub(super) fn runs<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    i: usize,
    j0: usize,
    blocks: &mut [B],
    outs: &mut [T::V3],
    x: &[T::V3],
    acc: &mut T::V3,
) -> Result<(), ParticleError> {
    let mut a = [*acc];
    runs_k::<T, B, 1>(src, i, j0, blocks, [outs], [x], &mut a)?;
    *acc = a[0];
    Ok(())
}

/// [`runs`] for `K` vectors: each block, evaluated once, applied to every `x_q` (sums
/// into `acc_q`) and, transposed, to every `x_qi` (into `outs_q`), each in the order
/// [`runs`] sums it alone.
#[inline(always)]
pub(super) fn runs_k<T: Real, B: Block<T>, const K: usize>(
    src: Pairs<'_, T>,
    i: usize,
    j0: usize,
    blocks: &mut [B],
    outs: [&mut [T::V3]; K],
    x: [&[T::V3]; K],
    acc: &mut [T::V3; K],
) -> Result<(), ParticleError> {
    let (level, eta, pi, ai) = (src.level, src.eta, src.pos[i], src.radius[i]);
    let xi = x.map(|xq| xq[i - j0]);
    for (c, bs) in blocks.chunks_mut(RUN).enumerate() {
        let j = j0 + c * RUN;
        let pos = &src.pos[j..j + bs.len()];
        let radius = &src.radius[j..j + bs.len()];
        let mut s2 = [T::ZERO; RUN];
        for (k, (&pj, &aj)) in pos.iter().zip(radius).enumerate() {
            s2[k] = pair_norm2(level, ai, aj, pi - pj)
                .ok_or(ParticleError::Nested { i: j + k, j: i })?;
        }
        let roots: [(T, T); RUN] = core::array::from_fn(|k| s2[k].root_and_inverse());
        let cols = bs.iter_mut().zip(pos.iter().zip(radius));
        if K == 1 {
            // Each block applied as soon as it is built.
            for (k, (b, (&pj, &aj))) in cols.enumerate() {
                let m = pair_tt_from(level, eta, ai, aj, pi - pj, s2[k], roots[k]);
                *b = B::store(m);
                let col = c * RUN + k;
                acc[0] += m * x[0][col];
                outs[0][col] += T::m3_tmul(m, xi[0]);
            }
            continue;
        }
        // Several vectors: the run's blocks first, then each vector's sums over them
        // (the same order per vector; a vector at a time keeps its sums in registers).
        for (k, (b, (&pj, &aj))) in cols.enumerate() {
            *b = B::store(pair_tt_from(level, eta, ai, aj, pi - pj, s2[k], roots[k]));
        }
        for q in 0..K {
            for (k, &b) in bs.iter().enumerate() {
                let col = c * RUN + k;
                acc[q] += b.mul(x[q][col]);
                outs[q][col] += b.tmul(xi[q]);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DVec3};

    /// Deterministic values in [-0.5, 0.5).
    fn values(seed: u64) -> impl FnMut() -> f64 {
        let mut next = crate::linalg::block::tests::lcg(seed);
        move || next().0
    }

    /// Whether two runs of vectors (or blocks) hold the same bits.
    fn same<V, const K: usize>(a: &[V], b: &[V], bits: fn(&V) -> [f64; K]) -> bool {
        let eq = |(x, y): (&V, &V)| bits(x).map(f64::to_bits) == bits(y).map(f64::to_bits);
        a.len() == b.len() && a.iter().zip(b).all(eq)
    }

    /// Rows `b0..n` of general (non-symmetric, as above a wall) blocks: the grouped band
    /// gives the row-by-row band's bits, with groups left over or none.
    #[test]
    fn grouped_rows_give_the_bits_of_the_row_by_row_band() {
        const N: usize = 45;
        let mut v = values(7);
        let a: [DMat3; tri(N)] =
            core::array::from_fn(|_| DMat3::from_cols_array(&core::array::from_fn(|_| v())));
        let x: [DVec3; N] = core::array::from_fn(|_| DVec3::new(v(), v(), v()));
        for (b0, b1) in [(0, N), (13, N), (20, 25), (37, 44), (30, 30 + ROWS)] {
            let (mut y0, mut y1) = ([DVec3::ZERO; N], [DVec3::ZERO; N]);
            let (mut z0, mut z1) = ([DVec3::ONE; N], [DVec3::ONE; N]);
            let (y0, y1) = (&mut y0[..b1 - b0], &mut y1[..b1 - b0]);
            let (z0, z1) = (&mut z0[..b0], &mut z1[..b0]);
            super::super::band::<f64, _>(&a, b0, &x, y0, z0);
            band_rows_k::<f64, _, 1>(&a, b0, [&x], [y1], [z1]);
            assert!(same(y0, y1, DVec3::to_array), "rows {b0}..{b1}");
            assert!(same(z0, z1, DVec3::to_array), "rows {b0}..{b1}");
        }
    }

    /// The fused band in runs: the blocks, products and first error of the row-by-row
    /// fused band, at every level of hydrodynamics.
    #[test]
    fn runs_give_the_blocks_bits_and_error_of_the_fused_band() {
        const N: usize = 43;
        let mut v = values(11);
        let mut pos: [DVec3; N] =
            core::array::from_fn(|k| DVec3::new(3.0 * v(), 3.0 * v(), 0.7 * k as f64));
        let radius: [f64; N] = core::array::from_fn(|_| 0.3 + 0.5 * (v() + 0.5));
        let x: [DVec3; N] = core::array::from_fn(|_| DVec3::new(v(), v(), v()));
        for nested in [false, true] {
            if nested {
                // Two nested pairs in one band, the later row's at a lower column.
                pos[33] = pos[30];
                pos[35] = pos[2];
            }
            for level in [Hydro::Rpy, Hydro::Oseen, Hydro::FreeDraining] {
                let src = Pairs {
                    level,
                    eta: 0.7,
                    pos: &pos,
                    radius: &radius,
                };
                for (b0, b1) in [(0, N), (11, N), (29, 40)] {
                    let rows = tri(b1) - tri(b0);
                    let (mut o0, mut o1) = ([DMat3::ZERO; tri(N)], [DMat3::ZERO; tri(N)]);
                    let (mut y0, mut y1) = ([DVec3::ZERO; N], [DVec3::ZERO; N]);
                    let (mut z0, mut z1) = ([DVec3::ONE; N], [DVec3::ONE; N]);
                    let (o0, o1) = (&mut o0[..rows], &mut o1[..rows]);
                    let (y0, y1) = (&mut y0[..b1 - b0], &mut y1[..b1 - b0]);
                    let (z0, z1) = (&mut z0[..b0], &mut z1[..b0]);
                    let r0 =
                        super::super::assembly::band_fused::<f64, DMat3>(src, o0, b0, &x, y0, z0);
                    let r1 = fused_rows::<f64, DMat3>(src, o1, b0, &x, y1, z1);
                    assert_eq!(r0, r1, "{level:?} rows {b0}..{b1}");
                    assert_eq!(r0.is_err(), nested && b1 > 33, "{level:?} rows {b0}..{b1}");
                    if r0.is_ok() {
                        assert!(
                            same(o0, o1, DMat3::to_cols_array),
                            "{level:?} rows {b0}..{b1}"
                        );
                        assert!(same(y0, y1, DVec3::to_array), "{level:?} rows {b0}..{b1}");
                        assert!(same(z0, z1, DVec3::to_array), "{level:?} rows {b0}..{b1}");
                    }
                }
            }
        }
    }
}
