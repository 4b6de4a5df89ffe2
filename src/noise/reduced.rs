//! The Lanczos noise's products on a reduced copy of the stored mobility, in `f32`
//! SIMD lanes.
//!
//! The noise is right only to the Lanczos tolerance (`1e-3` by default), so its
//! products need neither the full `f64` mobility nor `f64` arithmetic. Each free-space
//! block is symmetric (`a I + b r r^T` for RPY and Oseen, scalar on the diagonal), and
//! so is each Ewald block of a periodic box (in bits, `mobility::periodic`'s tests), so
//! the copy keeps its six distinct entries rounded to `f32` (24 bytes instead of the 48
//! of a stored symmetric `f64` block, `linalg::Sym`, or the 72 of a general one),
//! and the products run in `f32`, four blocks of a row at once (`glam::Vec4`: SSE2
//! does four `f32` operations where it does two `f64`, and the `f64` walk was compute
//! bound at 3.4 ns a block; this one takes 1.3 at N = 1024). Lanczos then computes
//! `M~^(1/2) z` with `M~` the rounded mobility; each product is right to about `1e-6`
//! relative (`f32` sums, `tests/kernel/lanczos_chain.rs` measures it), far below the
//! tolerance. Bits: the same on any number of threads (the bands of
//! [`parallel::product`], each summing its rows and transposed blocks in `f64`, added
//! in band order), and on any target (`Vec4` is IEEE `f32` lane by lane,
//! with no fused multiply-add).
//!
//! **Layout.** `f32` values are held in pairs as the bit patterns of the `T` (`f64`)
//! entries of `T::M3` slots (no `unsafe` view of the memory is needed). Row `i` holds
//! blocks `j = 0 ..= i` in groups of twelve blocks, four slots (36 entries) a group:
//! three chunks of four blocks, each chunk the six entries `[xx, yy, zz, xy, xz, yz]`
//! of its four blocks as a lane quadruple apiece (two `f64` entries). The diagonal
//! block is stored halved (it is met twice: in the row's own sum and as its transposed
//! block), the blocks past the diagonal as zeros: 24 bytes a block and at most eleven
//! blocks of padding a row. A band walks its rows one column tile (480 beads) at a
//! time, the tile's `x` and partial sums in lanes on the stack; its partial sums over
//! all columns are kept in `f64`. The storage, [`slots`]`(n)`, is the factor's slice
//! of the workspace, which a step by Lanczos noise does not need for a factor
//! (`for_noise`). `T` must be `f64` ([`usable`]); an `f32` kernel reads the mobility
//! itself.

use crate::linalg::{Block, tri};
use crate::parallel::{self, Parallel, band_start};
use crate::real::Real;
use glam::Vec4;

/// Fewest block rows the copy is used at: the mobility then takes 17.6 MB and more,
/// beyond what a step keeps in a shared last-level cache (32 MB here, two mobilities
/// and other processes' data in it). Below it the products read the mobility itself.
pub const REDUCED_MIN: usize = 700;

/// Blocks of a group: three chunks of four lanes (36 entries, four slots).
const GROUP: usize = 12;

/// Chunks of four blocks a group.
const CHUNKS: usize = GROUP / 4;

/// Slots of a group of blocks (eighteen lane quadruples).
const BLOCK_SLOTS: usize = 4;

/// Whether the reduced copy applies to `n` block rows: an `f64` kernel (two `f32` per
/// slot entry) and at least [`REDUCED_MIN`] rows.
#[inline(always)]
pub const fn usable<T: Real>(n: usize) -> bool {
    core::mem::size_of::<T>() == 8 && n >= REDUCED_MIN
}

/// Whether the Lanczos noise of a thermal step of `p` at `n` beads reads the copy
/// ([`slots`]`(n)` slots of its own, [`Layout`](crate::Layout)): an `f64` kernel of
/// enough beads ([`usable`], tested first, so that an `f32` kernel links no copy), a
/// stored mobility with symmetric blocks (no wall, no Ewald sums: free space, or free
/// draining in a box), and the midpoint drift (the uncorrected draw, a few products,
/// keeps no storage for it).
#[inline(always)]
pub(crate) const fn for_noise<T: Real>(p: &crate::Params<T>, n: usize) -> bool {
    usable::<T>(n)
        && matches!(p.method, crate::Method::Overdamped | crate::Method::Springs)
        && matches!(p.brownian, Some(b) if matches!(b.drift, crate::Drift::Midpoint))
        && p.lanczos_noise(n)
        && !p.matrix_free
        && p.place().free_blocks(p.hydro)
}

/// Groups of row `i` (blocks `0 ..= i`).
const fn groups(i: usize) -> usize {
    i / GROUP + 1
}

/// Groups of rows `0..i`: the sum of [`groups`], in closed form.
const fn row_start(i: usize) -> usize {
    let q = i / GROUP;
    i + GROUP * q * q.saturating_sub(1) / 2 + (i % GROUP) * q
}

/// Slots the copy of `n` block rows takes.
pub const fn slots(n: usize) -> usize {
    copy_start(n)
}

/// The bits of entry `p` of a run of slots (nine entries a slot; a quadruple's two
/// entries may straddle two slots, which costs a second load, not a shuffle).
#[inline(always)]
fn bits<T: Real>(s: &[T::M3], p: usize) -> u64 {
    T::m3_entries(&s[p / 9])[p % 9].to_f64().to_bits()
}

/// Lane quadruple `q`: the `f32` pairs of entries `2 q` and `2 q + 1`, lanes 0 and 1
/// in their low halves (so the compiler loads them with one instruction and one
/// shuffle).
#[inline(always)]
fn get4<T: Real>(s: &[T::M3], q: usize) -> [f32; 4] {
    let (a, b) = (bits::<T>(s, 2 * q), bits::<T>(s, 2 * q + 1));
    let f = |x: u64| f32::from_bits(x as u32);
    [f(a), f(b), f(a >> 32), f(b >> 32)]
}

/// Writes lane quadruple `q`.
#[inline(always)]
fn put4<T: Real>(s: &mut [T::M3], q: usize, v: [f32; 4]) {
    let pair = |a: f32, b: f32| {
        T::from_f64(f64::from_bits(
            u64::from(a.to_bits()) | (u64::from(b.to_bits()) << 32),
        ))
    };
    let (p, r) = (2 * q, 2 * q + 1);
    T::m3_entries_mut(&mut s[p / 9])[p % 9] = pair(v[0], v[2]);
    T::m3_entries_mut(&mut s[r / 9])[r % 9] = pair(v[1], v[3]);
}

/// First slot of row `i` in the copy.
pub(crate) const fn copy_start(i: usize) -> usize {
    BLOCK_SLOTS * row_start(i)
}

/// Packs rows `b0..b1` of the packed mobility (`mu`: those rows, from `tri(b0)`) into
/// `out` (their groups, from [`copy_start`]`(b0)`).
pub(crate) fn pack_rows<T: Real, B: Block<T>>(b0: usize, b1: usize, mu: &[B], out: &mut [T::M3]) {
    let base = BLOCK_SLOTS * row_start(b0);
    for i in b0..b1 {
        let row = &mu[tri(i) - tri(b0)..=tri(i) - tri(b0) + i];
        let slots = &mut out[BLOCK_SLOTS * row_start(i) - base..][..BLOCK_SLOTS * groups(i)];
        for (g, group) in slots.chunks_exact_mut(BLOCK_SLOTS).enumerate() {
            for c in 0..CHUNKS {
                let j0 = GROUP * g + 4 * c;
                // The six entries of the chunk's four blocks (halved on the diagonal,
                // zero past it).
                let mut e = [[0.0f32; 4]; 6];
                for l in 0..4 {
                    let j = j0 + l;
                    if j > i {
                        break;
                    }
                    let full = row[j].full();
                    let a = T::m3_entries(&full);
                    let half = if j == i { 0.5 } else { 1.0 };
                    // Column-major: xx, yy, zz, then xy (row 1, col 0), xz, yz.
                    for (k, &at) in [0, 4, 8, 1, 2, 5].iter().enumerate() {
                        e[k][l] = half * a[at].to_f64() as f32;
                    }
                }
                for (k, v) in e.into_iter().enumerate() {
                    put4::<T>(group, 6 * c + k, v);
                }
            }
        }
    }
}

/// Beads of a column tile (whole groups): a band's rows are walked tile by tile, with
/// the tile's `x` and partial sums `y` in lanes on the stack (11.5 kB; a tile twice as
/// long measured 1.30 against 1.36 ns a block at N = 1024 and 2.7 against 3.0 at 2048,
/// for twice the stack).
const TILE: usize = 40 * GROUP;

/// A tile's vector: per chunk of four beads, `x`, `y` and `z` as four lanes each.
type Lanes = [[Vec4; 3]; TILE / 4];

/// Row `i`'s blocks in one tile (`row`, whole groups) for `K` vectors: `sum_j B_ij x_qj`
/// (returned, from four lane sums in a fixed order) while `y_qj += B_ij x_qi`, each
/// vector's sums in the order of its own product (the vectors share the blocks' loads).
/// (Written with `Vec4`: left to the vectoriser, the same loop on `[f32; 4]` took twice
/// as long, shuffling.)
#[inline(always)]
fn walk_row<T: Real, const K: usize>(
    row: &[T::M3],
    x: [&Lanes; K],
    y: [&mut Lanes; K],
    xi: [[f32; 3]; K],
) -> [[f32; 3]; K] {
    let xi = xi.map(|v| v.map(Vec4::splat));
    let mut acc = [[Vec4::ZERO; 3]; K];
    for (g, b) in row.chunks_exact(BLOCK_SLOTS).enumerate() {
        for c in 0..CHUNKS {
            let [xx, yy, zz, xy, xz, yz]: [Vec4; 6] =
                core::array::from_fn(|q| Vec4::from_array(get4::<T>(b, 6 * c + q)));
            let h = CHUNKS * g + c;
            for q in 0..K {
                let (xl, yl) = (&x[q][h], &mut y[q][h]);
                for (k, r) in [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]
                    .iter()
                    .enumerate()
                {
                    acc[q][k] += r[0] * xl[0] + r[1] * xl[1] + r[2] * xl[2];
                    yl[k] += r[0] * xi[q][0] + r[1] * xi[q][1] + r[2] * xi[q][2];
                }
            }
        }
    }
    acc.map(|a| a.map(|a| (a.x + a.y) + (a.z + a.w)))
}

/// Rows `b0..b0 + y_q.len()` from their groups `rows` into `y_q`, the transposed blocks
/// left of the band into `z_q` (both from zero, in `f64`, as in [`parallel::product`]'s
/// bands), one column tile at a time, for `K` vectors at once.
#[inline(always)]
fn band<T: Real, const K: usize>(
    rows: &[T::M3],
    b0: usize,
    x: [&[T::V3]; K],
    mut y: [&mut [T::V3]; K],
    mut z: [&mut [T::V3]; K],
) {
    let b1 = b0 + y[0].len();
    for q in 0..K {
        y[q].fill(T::V3_ZERO);
        z[q].fill(T::V3_ZERO);
    }
    let base = BLOCK_SLOTS * row_start(b0);
    let lane = |q: usize, j: usize, k: usize| match x[q].get(j) {
        Some(&v) => T::xyz(v)[k].to_f64() as f32,
        None => 0.0,
    };
    // Adds `f32` sums to row `j` of the band's partial sum `q` (`z` above the band).
    let mut add = |q: usize, j: usize, v: [f32; 3]| {
        let out = if j < b0 {
            &mut z[q][j]
        } else {
            &mut y[q][j - b0]
        };
        *out += T::v3_from(v.map(f64::from));
    };
    for t0 in (0..b1).step_by(TILE) {
        let mut xt: [Lanes; K] = [[[Vec4::ZERO; 3]; TILE / 4]; K];
        let mut yt: [Lanes; K] = [[[Vec4::ZERO; 3]; TILE / 4]; K];
        for (q, xq) in xt.iter_mut().enumerate() {
            for (h, chunk) in xq.iter_mut().enumerate() {
                let lanes =
                    |k| Vec4::from_array(core::array::from_fn(|l| lane(q, t0 + 4 * h + l, k)));
                *chunk = core::array::from_fn(lanes);
            }
        }
        for i in b0.max(t0)..b1 {
            // The row's groups from the tile's first to its last or the row's end.
            let g = (groups(i) - t0 / GROUP).min(TILE / GROUP);
            let start = BLOCK_SLOTS * (row_start(i) + t0 / GROUP) - base;
            let row = &rows[start..][..BLOCK_SLOTS * g];
            let xi = core::array::from_fn(|q| core::array::from_fn(|k| lane(q, i, k)));
            let sums = walk_row::<T, K>(row, xt.each_ref(), yt.each_mut(), xi);
            for (q, v) in sums.into_iter().enumerate() {
                add(q, i, v);
            }
        }
        for j in t0..(t0 + TILE).min(b1) {
            let r = j - t0;
            for (q, yq) in yt.iter().enumerate() {
                add(q, j, core::array::from_fn(|k| yq[r / 4][k][r % 4]));
            }
        }
    }
}

/// `y = M~ x` from the copy `copy` of `n` block rows ([`copy_apply`] writes it), in the
/// bands of [`parallel::product`] through `par` (`z`:
/// [`parallel::band_scratch`]`(n)` vectors): each band's partial sums are kept in
/// `f64`, added in band order.
pub fn apply<T: Real>(
    par: &dyn Parallel,
    copy: &[T::M3],
    n: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    apply_k::<T, 1>(par, copy, n, [x], [y], z);
}

/// [`apply`] of `K` vectors in one pass over the copy (a block product: each block is
/// read once and applied to all `K`): `y[q]` gets the bits `apply` gives it for `x[q]`.
/// `z` holds at least `K` [`parallel::band_scratch`]`(n)` vectors.
pub fn apply_k<T: Real, const K: usize>(
    par: &dyn Parallel,
    copy: &[T::M3],
    n: usize,
    x: [&[T::V3]; K],
    y: [&mut [T::V3]; K],
    z: &mut [T::V3],
) {
    let _ = parallel::by_bands_then_reduce::<T, (), K>(par, n, y, z, |t, yt, zt| {
        apply_band::<T, K>(copy, n, t, x, yt, zt);
        Ok(())
    });
}

/// Band `t` of [`apply_k`] (as [`parallel::product_band`] is of [`parallel::products`];
/// inlined, for a host's wider-vector copy).
#[inline(always)]
pub fn apply_band<T: Real, const K: usize>(
    copy: &[T::M3],
    n: usize,
    t: usize,
    x: [&[T::V3]; K],
    y: [&mut [T::V3]; K],
    z: [&mut [T::V3]; K],
) {
    let b0 = band_start(n, t);
    band::<T, K>(&copy[copy_start(b0)..], b0, x.map(|xq| &xq[..n]), y, z);
}

/// [`apply`] while writing the copy of the packed mobility `mu` (`n` block rows) into
/// `copy` ([`slots`]`(n)` slots): each band packs its rows, then applies them from the
/// copy (so the product is the copy's, bit for bit).
pub fn copy_apply<T: Real>(
    par: &dyn Parallel,
    mu: &[impl Block<T>],
    n: usize,
    copy: &mut [T::M3],
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    let (x, copy) = (&x[..n], &mut copy[..slots(n)]);
    let _ = parallel::by_bands::<T, _, (), _>(par, n, copy, copy_start, y, z, |t, rows, yt, zt| {
        let (b0, b1) = (band_start(n, t), band_start(n, t + 1));
        pack_rows::<T, _>(b0, b1, &mu[tri(b0)..tri(b1)], rows);
        band::<T, 1>(rows, b0, [x], [yt], [zt]);
        Ok(())
    });
    parallel::reduce::<T>(n, y, z, par);
}

#[cfg(test)]
mod tests {
    /// The closed form of [`super::row_start`] against the sum it stands for.
    #[test]
    fn row_starts_sum_the_groups() {
        let mut sum = 0;
        for i in 0..200 {
            assert_eq!(super::row_start(i), sum, "i = {i}");
            sum += super::groups(i);
        }
    }
}
