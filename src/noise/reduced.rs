//! The Lanczos noise's products on a reduced copy of the stored mobility.
//!
//! The noise is right only to the Lanczos tolerance (`1e-3` by default), so its
//! products need not read the full `f64` mobility: each free-space block is symmetric
//! (`a I + b r r^T` for RPY and Oseen, scalar on the diagonal), and its six distinct
//! entries rounded to `f32` (relative `6e-8`) take 24 bytes instead of 72. Lanczos then
//! computes `M~^(1/2) z`, `M~` the rounded mobility (symmetric, positive definite with
//! `M` to `6e-8` relative), the arithmetic still in `T`. The products run in the bands
//! of [`parallel::product`], eight block rows at a time (the same walk, generic over
//! how a block is read): 3.4-3.6 ns per block at N = 1024 and 2048 against 3.9-4.4
//! for the full product, which is memory bound there. The copy's products are compute
//! bound (the entries are widened on the fly), so in cache they gain nothing, hence
//! [`REDUCED_MIN`].
//!
//! Storage: the blocks are read from and written to `T::M3` slots, three blocks per
//! slot (one per column), each block's six `f32` as three `f64` bit patterns (pairs of
//! `f32`). Row `i` (blocks `j = 0 ..= i`) starts at a slot of its own ([`slots`]`(i)`),
//! block `j` in its slot `j / 3`. This needs `T` to be `f64` ([`usable`]); an `f32`
//! kernel reads the mobility itself. The copy lives in the Cholesky factor's storage, free until the
//! midpoint's mobility is assembled there after the noise is drawn.

use crate::linalg::tri;
use crate::parallel::{self, Blocks, Parallel, band_start};
use crate::real::Real;

/// Fewest block rows the copy is used at: the mobility then takes 17.6 MB and more,
/// beyond what a step keeps in a shared last-level cache (32 MB here, two mobilities
/// and other processes' data in it). Below it the products read the mobility itself.
pub const REDUCED_MIN: usize = 700;

/// Whether the reduced copy applies to `n` block rows: an `f64` kernel (two `f32` per
/// slot entry) and at least [`REDUCED_MIN`] rows.
pub fn usable<T: Real>(n: usize) -> bool {
    core::mem::size_of::<T>() == 8 && n >= REDUCED_MIN
}

/// Slots (`T::M3`) the copy of `n` block rows takes: `ceil((i + 1) / 3)` for row `i`,
/// so also the slot row `n` starts at.
pub const fn slots(n: usize) -> usize {
    // sum over i < n of (i / 3 + 1), in closed form.
    let q = n / 3;
    n + 3 * q * q.saturating_sub(1) / 2 + (n % 3) * q
}

/// Two `f32` (rounded from `a` and `b`) in one `f64` bit pattern, as `T`.
#[inline(always)]
fn pack<T: Real>(a: T, b: T) -> T {
    let (a, b) = ((a.to_f64() as f32).to_bits(), (b.to_f64() as f32).to_bits());
    T::from_f64(f64::from_bits(u64::from(a) | (u64::from(b) << 32)))
}

/// The two `f32` of [`pack`], as `T`.
#[inline(always)]
fn unpack<T: Real>(x: T) -> (T, T) {
    let bits = x.to_f64().to_bits();
    let (a, b) = (
        f32::from_bits(bits as u32),
        f32::from_bits((bits >> 32) as u32),
    );
    (T::from_f64(f64::from(a)), T::from_f64(f64::from(b)))
}

/// The symmetric block's six entries (lower triangle of `m`), packed into a column.
#[inline(always)]
fn pack_block<T: Real>(m: T::M3) -> T::V3 {
    let g = |r, c| T::m3_get(m, r, c);
    T::v3(
        pack(g(0, 0), g(1, 1)),
        pack(g(2, 2), g(1, 0)),
        pack(g(2, 0), g(2, 1)),
    )
}

/// The six entries of a packed column: `[xx, yy, zz, xy, xz, yz]`.
#[inline(always)]
fn entries<T: Real>(v: T::V3) -> [T; 6] {
    let [p, q, r] = T::xyz(v);
    let ((xx, yy), (zz, xy), (xz, yz)) = (unpack(p), unpack(q), unpack(r));
    [xx, yy, zz, xy, xz, yz]
}

/// `b v` for the symmetric block of `entries`.
#[inline(always)]
fn sym_mul<T: Real>(e: [T; 6], v: T::V3) -> T::V3 {
    let [xx, yy, zz, xy, xz, yz] = e;
    let [a, b, c] = T::xyz(v);
    T::v3(
        xx * a + xy * b + xz * c,
        xy * a + yy * b + yz * c,
        xz * a + yz * b + zz * c,
    )
}

/// The copy's slots from row `base` on, read by the banded walk
/// ([`parallel::band_rows`]): block `j` of a row is column `j % 3` of its slot `j / 3`.
#[derive(Clone, Copy)]
struct Reduced<'a, T: Real> {
    slots: &'a [T::M3],
    base: usize,
}

impl<'a, T: Real> Blocks<'a, T> for Reduced<'a, T> {
    #[inline(always)]
    fn row(self, i: usize) -> &'a [T::M3] {
        &self.slots[slots(i) - self.base..][..i / 3 + 1]
    }
    #[inline(always)]
    fn apply(row: &[T::M3], j: usize, x: T::V3, xr: T::V3) -> (T::V3, T::V3) {
        let e = entries::<T>(T::m3_col_at(&row[j / 3], j));
        (sym_mul(e, x), sym_mul(e, xr))
    }
}

/// `y = M~ x` from the copy `packed` of `n` block rows ([`copy_apply`]), in the bands of
/// [`parallel::product`] through `par` (`z`: [`parallel::band_scratch`]`(n)` vectors).
pub fn apply<T: Real>(
    par: &dyn Parallel,
    packed: &[T::M3],
    n: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    let _ = parallel::by_bands::<T, (), _>(par, n, &mut [], tri, y, z, |t, _, yt, zt| {
        let b0 = band_start(n, t);
        let blocks = Reduced::<T> {
            slots: &packed[slots(b0)..],
            base: slots(b0),
        };
        parallel::band_rows::<T, _>(blocks, b0, x, yt, zt);
        Ok(())
    });
    parallel::reduce::<T>(n, y, z, par);
}

/// [`apply`] while writing the copy of the packed mobility `mu` (`n` block rows) into
/// `packed` ([`slots`]`(n)` slots): each band packs its rows, then applies them from
/// the copy (so the product is the copy's, bit for bit).
#[allow(clippy::too_many_arguments)]
pub fn copy_apply<T: Real>(
    par: &dyn Parallel,
    mu: &[T::M3],
    n: usize,
    packed: &mut [T::M3],
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    let packed = &mut packed[..slots(n)];
    let _ = parallel::by_bands::<T, (), _>(par, n, packed, slots, y, z, |t, out, yt, zt| {
        let b0 = band_start(n, t);
        for i in b0..b0 + yt.len() {
            let row = &mu[tri(i)..=tri(i) + i];
            let start = slots(i) - slots(b0);
            for (q, slot) in out[start..slots(i + 1) - slots(b0)].iter_mut().enumerate() {
                let col = |c: usize| match row.get(3 * q + c) {
                    Some(&m) => pack_block::<T>(m),
                    None => T::V3_ZERO,
                };
                *slot = T::m3_cols(col(0), col(1), col(2));
            }
        }
        let blocks = Reduced::<T> {
            slots: &*out,
            base: slots(b0),
        };
        parallel::band_rows::<T, _>(blocks, b0, x, yt, zt);
        Ok(())
    });
    parallel::reduce::<T>(n, y, z, par);
}

#[cfg(test)]
mod tests {
    /// The closed form of [`super::slots`] against the sum it stands for.
    #[test]
    fn slots_sum_the_rows() {
        let mut sum = 0;
        for n in 0..100 {
            assert_eq!(super::slots(n), sum, "n = {n}");
            sum += n / 3 + 1;
        }
    }
}
