//! The mobility's `O(N^2)` work in bands of block rows, and the interface through which
//! a host runs the bands on several threads ([`Parallel`]).
//!
//! The kernel stays single-threaded: it cuts the assembly of `mu_tt` and the products
//! `y = mu_tt x` into independent jobs and hands them to the workspace's [`Parallel`]
//! ([`Workspace::with_parallel`](crate::Workspace::with_parallel); [`Serial`], one job
//! after the other, by default). A host implements [`Parallel`] with a thread pool (the
//! host crate `hydrorattle-parallel` does, with a pool in which the calling thread takes
//! part).
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
//! metric). This file holds the bands and the products of stored blocks; the assembly,
//! which evaluates the pair blocks (and may apply them on the way), is in
//! `parallel/assembly.rs`, apart because it is where the blocks come from, not how they
//! are read: it can fail on a nested pair, and its fused form follows the product's
//! order so that its bits are the product's.

mod assembly;
mod blocked;
mod free;
mod jobs;
mod lanes;
mod source;

pub use assembly::{assemble, assemble_apply};
pub(crate) use blocked::assemble_apply_then;
pub use free::{free_band, free_product, free_products};
#[cfg(feature = "pse")]
pub(crate) use jobs::{Jobs, run_all};
pub(crate) use jobs::{Packed, by_bands, by_bands_and, by_bands_k, by_rows, map_bands, reduce};
pub(crate) use source::{Blocks, assemble_blocks, block_at, product_blocks, serial_product};

// The band kernel is the dense product's (`sym_matvec` is its one-band case), so it
// lives in `linalg`.
pub(crate) use crate::linalg::packed::band;
use crate::linalg::{Block, tri};
use crate::real::Real;
use crate::rpy::{Hydro, self_tt};

/// A way to run independent jobs, possibly at the same time.
pub trait Parallel: core::fmt::Debug {
    /// Runs every job exactly once, in any order or at once, and returns when all are
    /// done. The jobs share no mutable state, so any schedule gives the same result.
    fn run(&self, jobs: &mut [&mut (dyn FnMut() + Send)]);

    /// Threads the jobs may run on at once (1 by default), for a host that chooses a
    /// product path by the thread count (`hydrorattle_parallel::model`). Nothing in the
    /// kernel's results depends on it.
    fn threads(&self) -> usize {
        1
    }
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

/// The pairs a fused band evaluates its blocks from: free space's blocks
/// ([`Blocks`]).
#[derive(Clone, Copy)]
pub(crate) struct Pairs<'a, T: Real> {
    pub(crate) level: Hydro,
    pub(crate) eta: T,
    pub(crate) pos: &'a [T::V3],
    pub(crate) radius: &'a [T],
}

impl<'a, T: Real> Pairs<'a, T> {
    /// Free space's blocks at `level` and viscosity `eta`.
    #[inline(always)]
    pub(crate) fn new(level: Hydro, eta: T, pos: &'a [T::V3], radius: &'a [T]) -> Self {
        Self {
            level,
            eta,
            pos,
            radius,
        }
    }

    /// The diagonal blocks of rows `b0..b0 + y.len()` into `rows` (the packed rows from
    /// `b0` on), `y` started from their products, `z` zeroed: a fused band's first step.
    #[inline(always)]
    fn start<B: Block<T>>(
        &self,
        rows: &mut [B],
        b0: usize,
        x: &[T::V3],
        y: &mut [T::V3],
        z: &mut [T::V3],
    ) {
        let base = tri(b0);
        z.fill(T::V3_ZERO);
        for (k, yk) in y.iter_mut().enumerate() {
            let i = b0 + k;
            let diag = T::m3_diag(self_tt(self.eta, self.radius[i]));
            rows[tri(i) - base + i] = B::store(diag);
            *yk = diag * x[i];
        }
    }
}

/// `y = A x` for the packed symmetric `A` of `n` block rows, in bands through `par`;
/// `z` holds at least [`band_scratch`]`(n)` vectors. Bit-identical to
/// [`sym_matvec`](crate::linalg::sym_matvec) below [`BANDED_MIN`] rows; from there on the
/// same bits on any number of threads.
pub fn product<T: Real>(
    par: &dyn Parallel,
    a: &[impl Block<T>],
    n: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    if bands(n) == 1 {
        band::<T, _>(a, 0, x, &mut y[..n], &mut []);
        return;
    }
    products::<T, 1>(par, a, n, [x], [y], z);
}

/// [`product`] of `K` vectors in one pass over the blocks (a block product: each block
/// is read once and applied to all `K`): `y[q]` gets the bits `product` gives it for
/// `x[q]`, at every `n` and on any number of threads. `z` holds at least `K`
/// [`band_scratch`]`(n)` vectors.
pub fn products<T: Real, const K: usize>(
    par: &dyn Parallel,
    a: &[impl Block<T>],
    n: usize,
    x: [&[T::V3]; K],
    y: [&mut [T::V3]; K],
    z: &mut [T::V3],
) {
    let _ = by_bands_then_reduce::<T, (), K>(par, n, y, z, |t, yt, zt| {
        product_band::<T, K>(a, n, t, x, yt, zt);
        Ok(())
    });
}

/// Band `t` of [`products`] (`y`: its rows of each product, `z`: its partial sums, as
/// [`by_bands_then_reduce`] hands them out). Inlined into its caller, so that a host
/// can compile it inside a function with wider vector instructions enabled
/// (`hydrorattle_parallel::wide`) and get the same bits: the arithmetic and its order
/// are the same.
#[inline(always)]
pub fn product_band<T: Real, const K: usize>(
    a: &[impl Block<T>],
    n: usize,
    t: usize,
    x: [&[T::V3]; K],
    y: [&mut [T::V3]; K],
    z: [&mut [T::V3]; K],
) {
    blocked::band_rows_k::<T, _, K>(a, band_start(n, t), x, y, z);
}

/// The `K` products `y` of [`products`] and its kin: `band(t, y_t, z_t)` for every band
/// `t` of `n` rows (its rows of each `y_q`, its partial sums of each `z_q`, `z` cut into
/// [`band_scratch`]`(n)` vectors a product) through `par`, then each product's partial
/// sums added in band order; one band is run on the calling thread. The first error in
/// band order. With `band` one of [`product_band`], [`free_band`] or
/// [`reduced::apply_band`](crate::noise::reduced::apply_band) this is [`products`],
/// [`free_products`] or [`reduced::apply_k`](crate::noise::reduced::apply_k).
pub fn by_bands_then_reduce<T: Real, E: Send, const K: usize>(
    par: &dyn Parallel,
    n: usize,
    y: [&mut [T::V3]; K],
    z: &mut [T::V3],
    band: impl Fn(usize, [&mut [T::V3]; K], [&mut [T::V3]; K]) -> Result<(), E> + Sync,
) -> Result<(), E> {
    let mut y = y.map(|yq| &mut yq[..n]);
    let ys = y.each_mut().map(|yq| &mut **yq);
    if bands(n) == 1 {
        return band(0, ys, [(); K].map(|_| &mut [][..]));
    }
    let none = || (&mut [][..], tri as fn(usize) -> usize);
    let zs = scratches::<T, K>(n, z);
    by_bands_k::<T, (), (), E, _, K>(par, n, none(), none(), ys, zs, |t, _, _, yt, zt| {
        band(t, yt, zt)
    })?;
    let zs = scratches::<T, K>(n, z);
    for (yq, zq) in y.into_iter().zip(zs) {
        reduce::<T>(n, yq, zq, par);
    }
    Ok(())
}

/// `K` consecutive runs of [`band_scratch`]`(n)` vectors of `z`, one per product.
fn scratches<T: Real, const K: usize>(n: usize, z: &mut [T::V3]) -> [&mut [T::V3]; K] {
    let s = band_scratch(n);
    let mut rest = &mut z[..K * s];
    core::array::from_fn(|_| {
        let (head, tail) = core::mem::take(&mut rest).split_at_mut(s);
        rest = tail;
        head
    })
}
