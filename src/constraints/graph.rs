//! The Krylov preconditioner on the constraint graph, for lists with one-sided rows
//! (contact piles, `docs/CONTACTS.md`): incomplete Cholesky, IC(0), of `A` restricted
//! to the pairs of rows that share a sphere.
//!
//! In a pile a sphere's rows (its wall link, its contacts, its bonds) sit anywhere in
//! the list, so the band `|k - l| <= BAND` of the bond-ordered solve holds little of
//! `A`'s coupling there. The rows that share a sphere are coupled through that
//! sphere's self mobility; every other entry is a pair mobility, which between
//! touching spheres is still about half the self mobility and decays only as `1 / r`
//! (so a pattern of near rows holds part of `A`, not most of it: the measured gain,
//! `docs/CONTACTS.md`, is a fifth of the products).
//!
//! * Pattern: row `k` keeps the rows `l < k` that share a sphere with it, at most
//!   [`WIDTH`] of them, the nearest in list order (a row with more neighbours below it
//!   than that loses its farthest: fixed by the list, so the same bits every time).
//!   Found once a solve through per-sphere lists of rows (`n + 2 B` indices).
//! * Values: `A`'s entries on that pattern (pair terms included), masked as the band's
//!   are (an inactive one-sided row keeps its diagonal alone), factorised in place
//!   without fill (IC(0)): `O(B WIDTH^2)`.
//! * A factor that is not positive definite (IC(0) of a positive definite matrix can
//!   break down) gives way to the diagonal (Jacobi), as the band does; pivots of
//!   dependent rows are regularised as there.
//!
//! The storage is the band's: row `k` of the factor takes the band's `BAND + 1`
//! scalars (`WIDTH` off-diagonal entries, then the diagonal), its column indices
//! `WIDTH` indices (`usize::MAX`: none).

use super::{Metric, onesided};
use crate::bonds::Bond;
use crate::real::Real;

/// Off-diagonal entries kept per row of the factor (the band's half-width, whose
/// storage it takes). In the measured piles a contact row has at most this many
/// neighbours below it in all but a few rows (`examples/pile_cost.rs`).
pub(super) const WIDTH: usize = super::krylov::BAND;

/// No column: an unused slot of a row's pattern.
const NONE: usize = usize::MAX;

/// Index scratch for `rows` rows on `n` spheres: the column indices, each row's links
/// in the per-sphere lists and the lists' heads; none without contacts.
pub(crate) const fn indices(n: usize, rows: usize) -> usize {
    if cfg!(feature = "contacts") {
        WIDTH * rows + 2 * rows + n
    } else {
        0
    }
}

/// The spheres a row touches: `i`, and `j` unless it pushes on one sphere.
#[inline]
fn ends<T: Real>(b: &Bond<T>) -> [Option<usize>; 2] {
    [Some(b.i), (!b.one_sphere()).then_some(b.j)]
}

/// Builds the pattern in `cols` (`WIDTH` per row, ascending, [`NONE`] after the last)
/// for `bonds` on `n` spheres; `links` is scratch of `2 B + n`.
pub(super) fn pattern<T: Real>(
    bonds: &[Bond<T>],
    n: usize,
    cols: &mut [usize],
    links: &mut [usize],
) {
    let nb = bonds.len();
    let (next, head) = links.split_at_mut(2 * nb);
    head[..n].fill(NONE);
    // Rows in ascending order, each pushed in front of its spheres' lists: every list
    // runs from the latest row down.
    for (k, b) in bonds.iter().enumerate() {
        for (side, s) in ends(b).into_iter().enumerate() {
            if let Some(s) = s.filter(|&s| s < n) {
                next[2 * k + side] = head[s];
                head[s] = 2 * k + side;
            }
        }
    }
    for (k, b) in bonds.iter().enumerate() {
        let row = &mut cols[k * WIDTH..(k + 1) * WIDTH];
        row.fill(NONE);
        // The two lists from row `k`'s own links down, merged in descending order.
        let [a, c] = [0, 1].map(|side| match ends(b)[side] {
            Some(s) if s < n => next[2 * k + side],
            _ => NONE,
        });
        let (mut a, mut c) = (a, c);
        let mut kept = 0;
        while kept < WIDTH && (a != NONE || c != NONE) {
            let (ra, rc) = (row_of(a), row_of(c));
            // The larger row next (`NONE` maps to no row).
            let l = match (ra, rc) {
                (Some(x), Some(y)) => x.max(y),
                (Some(x), None) | (None, Some(x)) => x,
                (None, None) => break,
            };
            if ra == Some(l) {
                a = next[a];
            }
            if rc == Some(l) {
                c = next[c];
            }
            // A row that touches both spheres of `k` appears in both lists once.
            row[WIDTH - 1 - kept] = l;
            kept += 1;
        }
        // Ascending, unused slots last.
        row.copy_within(WIDTH - kept.., 0);
        row[kept..].fill(NONE);
    }
}

/// The row a list link belongs to.
#[inline]
fn row_of(link: usize) -> Option<usize> {
    (link != NONE).then_some(link / 2)
}

/// `A` on the pattern `cols`, masked, factorised into `pre` (`WIDTH + 1` per row);
/// the diagonal's square roots where the factor is not positive definite. Returns the
/// largest diagonal entry of `A` (NaN-sticky), the bound the curvature test reads.
pub(super) fn factor<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    c: T,
    (pre, cols): (&mut [T], &[usize]),
    (from, state): (usize, &[usize]),
) -> T {
    let nb = bonds.len();
    let off = |k: usize| k >= from && !onesided::active(state[k]);
    let mut top = T::ZERO;
    for k in 0..nb {
        let dir = metric.grad(k) * c;
        let row = &mut pre[k * (WIDTH + 1)..(k + 1) * (WIDTH + 1)];
        for (t, &l) in cols[k * WIDTH..(k + 1) * WIDTH].iter().enumerate() {
            row[t] = T::ZERO;
            if l != NONE && !off(k) && !off(l) {
                metric.jacobian_row(bonds, k, dir, l, &mut row[t..=t]);
            }
        }
        metric.jacobian_row(bonds, k, dir, k, &mut row[WIDTH..]);
        top = top.max_sticky(row[WIDTH]);
    }
    let floor = super::dependent::rank_floor::<T>();
    if incomplete(pre, cols, nb, floor).is_err() {
        log::debug!("krylov: graph preconditioner not positive definite, using Jacobi");
        for (k, row) in pre[..nb * (WIDTH + 1)]
            .chunks_exact_mut(WIDTH + 1)
            .enumerate()
        {
            row[..WIDTH].fill(T::ZERO);
            // A's diagonal is positive (a row's own metric); a degenerate row gives 1.
            let mut d = [T::ZERO];
            metric.jacobian_row(bonds, k, metric.grad(k) * c, k, &mut d);
            row[WIDTH] = if d[0] > T::ZERO && d[0].is_finite() {
                d[0].sqrt()
            } else {
                T::ONE
            };
        }
    }
    top
}

/// IC(0) in place: `L` on the pattern with `L L^T = A` there. A pivot within `floor`
/// times its diagonal of zero (a dependent row) is replaced by that diagonal, as
/// [`band::regularised`](crate::linalg::band::regularised) does; below that, an error.
fn incomplete<T: Real>(pre: &mut [T], cols: &[usize], nb: usize, floor: T) -> Result<(), ()> {
    let w = WIDTH + 1;
    for k in 0..nb {
        let ck = &cols[k * WIDTH..(k + 1) * WIDTH];
        for t in 0..WIDTH {
            let l = ck[t];
            if l == NONE {
                break;
            }
            // `sum_j L_kj L_lj` over the columns `j < l` both rows hold (both ascending).
            let cl = &cols[l * WIDTH..(l + 1) * WIDTH];
            let (mut s, mut u) = (pre[k * w + t], 0);
            for (v, &j) in ck[..t].iter().enumerate() {
                while u < WIDTH && cl[u] < j {
                    u += 1;
                }
                if u < WIDTH && cl[u] == j {
                    s -= pre[k * w + v] * pre[l * w + u];
                }
            }
            pre[k * w + t] = s / pre[l * w + WIDTH];
        }
        let diagonal = pre[k * w + WIDTH];
        let mut s = diagonal;
        for t in 0..WIDTH {
            s -= pre[k * w + t] * pre[k * w + t];
        }
        pre[k * w + WIDTH] = if s > floor * diagonal && s.is_finite() {
            s.sqrt()
        } else if floor > T::ZERO && diagonal > T::ZERO && s > -floor * diagonal {
            diagonal.sqrt()
        } else {
            return Err(());
        };
    }
    Ok(())
}

/// Solves `L L^T z = z` in place with the factor from [`factor`].
pub(super) fn solve<T: Real>(pre: &[T], cols: &[usize], z: &mut [T]) {
    let w = WIDTH + 1;
    let nb = z.len();
    for k in 0..nb {
        let mut acc = z[k];
        for (t, &l) in cols[k * WIDTH..(k + 1) * WIDTH].iter().enumerate() {
            if l == NONE {
                break;
            }
            acc -= pre[k * w + t] * z[l];
        }
        z[k] = acc / pre[k * w + WIDTH];
    }
    for k in (0..nb).rev() {
        let zk = z[k] / pre[k * w + WIDTH];
        z[k] = zk;
        for (t, &l) in cols[k * WIDTH..(k + 1) * WIDTH].iter().enumerate() {
            if l == NONE {
                break;
            }
            z[l] -= pre[k * w + t] * zk;
        }
    }
}
