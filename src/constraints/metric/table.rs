//! The dense table of `D_l(p)` the dense solvers read at every iteration, built once a
//! step from the packed mobility ([`Metric::Dense`](super::Metric::Dense)). Its own
//! module because it walks the packed triangle in runs (no per-entry choice of
//! triangle), a loop of its own, never inlined, unlike the entry reads.

use super::{sym_block, sym_diff_mul};
use crate::bonds::Bond;
use crate::linalg::{Block, Mob, tri};
use crate::real::Real;

/// Tabulates `disp[l * n + q] = (mu_qi - mu_qj) (scale g_l)` from the packed mobility:
/// the values [`Metric::Mobility`](super::Metric::Mobility) gives (one block difference
/// and one block product per entry, not two products). Blocks stored as `mu_qi` are
/// transposed for [`sym_diff_mul`] (exact: the same bits for symmetric blocks; only a
/// wall's blocks are not symmetric, so without the `wall` feature, or with `sym` (no
/// wall in this step), nothing is transposed and only lower triangles are read). Never
/// inlined: the metric's constructor is inlined at every call site
/// (`mobility_metric`), the table is the same code at each.
#[inline(never)]
pub(crate) fn tabulate<T: Real>(
    mu: Mob<'_, T>,
    bonds: &[Bond<T>],
    grad: &[T::V3],
    scale: T,
    n: usize,
    sym: bool,
    disp: &mut [T::V3],
) {
    // One body per case, so that the block reads branch on nothing at run time.
    match mu {
        Mob::Sym(mu) => table::<T, _, true>(mu, bonds, grad, scale, n, disp),
        Mob::Full(mu) if sym || !crate::geometry::GENERAL_BLOCKS => {
            table::<T, _, true>(mu, bonds, grad, scale, n, disp)
        }
        Mob::Full(mu) => table::<T, _, false>(mu, bonds, grad, scale, n, disp),
    }
}

/// [`tabulate`] with the blocks known symmetric (`SYM`) or not.
#[inline(always)]
fn table<T: Real, B: Block<T>, const SYM: bool>(
    mu: &[B],
    bonds: &[Bond<T>],
    grad: &[T::V3],
    scale: T,
    n: usize,
    disp: &mut [T::V3],
) {
    let nb = bonds.len();
    let disp = &mut disp[..n * nb];
    let sym = SYM;
    let tr = |m: T::M3| {
        if crate::geometry::GENERAL_BLOCKS && !sym {
            T::transpose(m)
        } else {
            m
        }
    };
    for (l, b) in bonds.iter().enumerate() {
        let g = grad[l] * scale;
        // Bead `q`'s entry of this bond is `disp[l * n + q]` (bond-major).
        let out = &mut disp[l * n..(l + 1) * n];
        if b.one_sphere() {
            for (q, o) in out.iter_mut().enumerate() {
                *o = sym_diff_mul::<T>(sym_block::<T, B>(mu, q, b.i), T::M3_ZERO, g, false);
            }
            continue;
        }
        let (i, j) = (b.i, b.j);
        let (lo, hi) = (i.min(j), i.max(j));
        // The values of `sym_block(q, i) - sym_block(q, j)`, read in three runs of `q` so
        // that no entry decides which triangle holds its blocks: up to `lo` both are in
        // rows `i` and `j` (contiguous); up to `hi` one is in row `hi`, the other in
        // column `lo`; beyond, both in columns `i` and `j` of the rows below.
        let (ri, rj) = (tri(i), tri(j));
        let mut at = 0;
        for (&a, &c) in mu[ri..=ri + lo].iter().zip(&mu[rj..=rj + lo]) {
            out[at] = sym_diff_mul::<T>(a.full(), c.full(), g, sym);
            at += 1;
        }
        let row_hi = &mu[tri(hi)..tri(hi) + hi + 1];
        let mut rq = tri(lo + 1);
        for q in lo + 1..=hi {
            let (on_row, on_col) = (row_hi[q].full(), mu[rq + lo].full());
            let on_col = tr(on_col);
            out[at] = if i == hi {
                sym_diff_mul::<T>(on_row, on_col, g, sym)
            } else {
                sym_diff_mul::<T>(on_col, on_row, g, sym)
            };
            rq += q + 1;
            at += 1;
        }
        for q in hi + 1..n {
            out[at] = sym_diff_mul::<T>(tr(mu[rq + i].full()), tr(mu[rq + j].full()), g, sym);
            rq += q + 1;
            at += 1;
        }
    }
}
