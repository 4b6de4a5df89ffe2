//! The Lanczos noise's products on a reduced copy of the stored mobility.
//!
//! The noise is right only to the Lanczos tolerance (`1e-3` by default), so its
//! products need not read the full `f64` mobility: each free-space block is symmetric
//! (`a I + b r r^T` for RPY and Oseen, scalar on the diagonal), and its six distinct
//! entries rounded to `f32` (relative `6e-8`) take 24 bytes instead of 72. Lanczos then
//! computes `M~^(1/2) z`, `M~` the rounded mobility (symmetric, positive definite with
//! `M` to `6e-8` relative), the arithmetic still in `T`. Out of cache the products are
//! memory bound and run about twice as fast; in cache they are compute bound and about
//! 20 % slower (the entries are widened on the fly), hence [`REDUCED_MIN`].
//!
//! Storage: the blocks are read from and written to `T::M3` slots, three blocks per
//! slot (one per column), each block's six `f32` as three `f64` bit patterns (pairs of
//! `f32`). Row `i` (blocks `j = 0 ..= i`) starts at a slot of its own, so a row is read
//! slot by slot. This needs `T` to be `f64` ([`usable`]); an `f32` kernel reads the
//! mobility itself. The copy lives in the Cholesky factor's storage, free until the
//! midpoint's mobility is assembled there after the noise is drawn.

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

/// Slots (`T::M3`) the copy of `n` block rows takes: `ceil((i + 1) / 3)` for row `i`.
pub const fn slots(n: usize) -> usize {
    let mut s = 0;
    let mut i = 0;
    while i < n {
        s += (i + 3) / 3;
        i += 1;
    }
    s
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
fn sym_mul<T: Real>(e: [T; 6], v: [T; 3]) -> [T; 3] {
    let [xx, yy, zz, xy, xz, yz] = e;
    [
        xx * v[0] + xy * v[1] + xz * v[2],
        xy * v[0] + yy * v[1] + yz * v[2],
        xz * v[0] + yz * v[1] + zz * v[2],
    ]
}

/// `a += b`, componentwise.
#[inline(always)]
fn add<T: Real>(a: &mut [T; 3], b: [T; 3]) {
    for (x, y) in a.iter_mut().zip(b) {
        *x += y;
    }
}

/// `y = M~ x` from the copy `packed` of `n` block rows ([`copy_apply`]).
pub fn apply<T: Real>(packed: &[T::M3], n: usize, x: &[T::V3], y: &mut [T::V3]) {
    y[..n].fill(T::V3_ZERO);
    let mut at = 0;
    for i in 0..n {
        let len = (i + 3) / 3;
        apply_row::<T>(&packed[at..at + len], i, x, y);
        at += len;
    }
}

/// `y = M~ x` while writing the copy of the packed mobility `mu` (`n` block rows) into
/// `packed` ([`slots`]`(n)` slots): one pass over `mu`, each row applied from its copy
/// as soon as it is written (so the product is the copy's, bit for bit).
pub fn copy_apply<T: Real>(
    mu: &[T::M3],
    n: usize,
    packed: &mut [T::M3],
    x: &[T::V3],
    y: &mut [T::V3],
) {
    y[..n].fill(T::V3_ZERO);
    let mut at = 0;
    for i in 0..n {
        let row = &mu[i * (i + 1) / 2..][..=i];
        let len = (i + 3) / 3;
        let out = &mut packed[at..at + len];
        for (q, slot) in out.iter_mut().enumerate() {
            let col = |c: usize| match row.get(3 * q + c) {
                Some(&m) => pack_block::<T>(m),
                None => T::V3_ZERO,
            };
            *slot = T::m3_cols(col(0), col(1), col(2));
        }
        apply_row::<T>(out, i, x, y);
        at += len;
    }
}

/// Row `i` of `M~ x` (its slots `row`): `y_i += sum_(j <= i) b_ij x_j` and
/// `y_j += b_ij x_i` for `j < i` (the upper triangle by symmetry).
#[inline(always)]
fn apply_row<T: Real>(row: &[T::M3], i: usize, x: &[T::V3], y: &mut [T::V3]) {
    let xi = T::xyz(x[i]);
    let mut acc = [T::ZERO; 3];
    // Whole slots of blocks j < i, then the last slot: the rest, the diagonal.
    let whole = i / 3;
    let (ys, yi) = y[..=i].split_at_mut(i);
    let mut block = |e: [T; 6], xj: T::V3, yj: &mut T::V3| {
        add(&mut acc, sym_mul(e, T::xyz(xj)));
        let [a, b, c] = sym_mul(e, xi);
        *yj += T::v3(a, b, c);
    };
    for ((&m, yq), xq) in row[..whole]
        .iter()
        .zip(ys.chunks_exact_mut(3))
        .zip(x.chunks_exact(3))
    {
        for c in 0..3 {
            block(entries::<T>(T::m3_col(m, c)), xq[c], &mut yq[c]);
        }
    }
    let last = row[whole];
    for c in 0..i - 3 * whole {
        let j = 3 * whole + c;
        block(entries::<T>(T::m3_col(last, c)), x[j], &mut ys[j]);
    }
    add(
        &mut acc,
        sym_mul(entries::<T>(T::m3_col(last, i - 3 * whole)), xi),
    );
    yi[0] += T::v3(acc[0], acc[1], acc[2]);
}
