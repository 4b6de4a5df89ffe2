//! The packed lower triangle of a symmetric block matrix written out dense, row-major,
//! in bands of rows through a [`Parallel`].
//!
//! Why bands on threads: above 32 MiB (N = 683 beads, `(3N)^2` f64) glibc's allocator
//! hands out fresh pages of an `mmap` for every new array (its mmap threshold stops
//! growing there), and the first write to each page faults and zeroes it. That, not
//! the arithmetic, is the jump from 2 to 6 ns per entry seen from N = 700: NumPy's own
//! `np.empty(n).fill(1.0)` jumps the same way at the same size (0.2 to 2.1 ns per
//! entry on a loaded 2-core machine). Nothing in a new array avoids the faults, but
//! bands on several threads take them in parallel.
//!
//! Why tiles: the upper triangle's block `(i, j)`, `j > i`, is the transpose of the
//! stored `(j, i)`; walking the output row by row reads those from a different packed
//! row per block, which misses the cache once the packed matrix outgrows it. Tiles of
//! [`TILE`] x [`TILE`] blocks read [`TILE`] packed rows and write `3 TILE` output rows,
//! each a run of `3 TILE` entries.

use hydrorattle::linalg::tri;
use hydrorattle::{Parallel, Real};

/// Blocks per tile edge: a tile reads 16 x 16 blocks of 72 bytes (f64), 18 KB.
const TILE: usize = 16;

/// Bands of output rows (a fixed count: the output does not depend on the threads).
const BANDS: usize = 16;

/// Block rows `i0..` of the dense matrix into `out` (whole output rows, starting at
/// block row `i0`), in tiles.
fn band<T: Real>(packed: &[T::M3], blocks: usize, i0: usize, out: &mut [T]) {
    let m = 3 * blocks;
    let i1 = i0 + out.len() / (3 * m);
    for t0 in (i0..i1).step_by(TILE) {
        for j0 in (0..blocks).step_by(TILE) {
            for i in t0..(t0 + TILE).min(i1) {
                for j in j0..(j0 + TILE).min(blocks) {
                    let b = match j <= i {
                        true => packed[tri(i) + j],
                        false => T::transpose(packed[tri(j) + i]),
                    };
                    for r in 0..3 {
                        let row = &mut out[(3 * (i - i0) + r) * m + 3 * j..][..3];
                        for (c, o) in row.iter_mut().enumerate() {
                            *o = T::m3_get(b, r, c);
                        }
                    }
                }
            }
        }
    }
}

/// The `(3 blocks) x (3 blocks)` dense matrix of the packed symmetric `packed`
/// (`tri(blocks)` blocks) into `out` (`(3 blocks)^2` values: NumPy's new array, whose
/// fresh pages the bands fault in parallel), row-major, its [`BANDS`] bands of rows run
/// through `par`.
pub fn write_dense<T: Real>(packed: &[T::M3], blocks: usize, par: &dyn Parallel, out: &mut [T]) {
    let m = 3 * blocks;
    debug_assert_eq!(out.len(), m * m);
    if blocks == 0 {
        return;
    }
    let rows = blocks.div_ceil(BANDS);
    let mut jobs: Vec<_> = out
        .chunks_mut(3 * rows * m)
        .enumerate()
        .map(|(k, chunk)| move || band::<T>(packed, blocks, k * rows, chunk))
        .collect();
    let mut refs: Vec<&mut (dyn FnMut() + Send)> = jobs
        .iter_mut()
        .map(|j| j as &mut (dyn FnMut() + Send))
        .collect();
    par.run(&mut refs);
}
