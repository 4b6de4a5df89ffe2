//! The packed lower triangle of a symmetric block matrix written out dense, row-major.
//!
//! Why tiles: the upper triangle's block `(i, j)`, `j > i`, is the transpose of the
//! stored `(j, i)`; walking the output row by row reads those from a different packed
//! row per block, which misses the cache once the packed matrix outgrows it (about
//! N = 700 beads: 18 MB), and the write slowed from 2 to 6 ns per entry there. Tiles
//! of [`TILE`] x [`TILE`] blocks read [`TILE`] packed rows and write `3 TILE` output
//! rows, each a run of `3 TILE` entries, so both stay in cache.

use hydrorattle::Real;
use hydrorattle::linalg::tri;

/// Blocks per tile edge: a tile reads 16 x 16 blocks of 72 bytes (f64), 18 KB.
const TILE: usize = 16;

/// The `(3 blocks) x (3 blocks)` dense matrix of the packed symmetric `packed`
/// (`tri(blocks)` blocks), row-major.
pub fn write_dense<T: Real>(packed: &[T::M3], blocks: usize) -> Vec<T> {
    let m = 3 * blocks;
    let mut out = vec![T::ZERO; m * m];
    for i0 in (0..blocks).step_by(TILE) {
        for j0 in (0..blocks).step_by(TILE) {
            for i in i0..(i0 + TILE).min(blocks) {
                for j in j0..(j0 + TILE).min(blocks) {
                    let b = match j <= i {
                        true => packed[tri(i) + j],
                        false => T::transpose(packed[tri(j) + i]),
                    };
                    for r in 0..3 {
                        let row = &mut out[(3 * i + r) * m + 3 * j..][..3];
                        for (c, o) in row.iter_mut().enumerate() {
                            *o = T::m3_get(b, r, c);
                        }
                    }
                }
            }
        }
    }
    out
}
