//! A cell list for the step's pair searches: the hard contacts' search
//! (`integrate::contacts`) and the acceptance's overlap check (`integrate::checks`).
//! Without it both visit every pair, `O(N^2)`: at 10^4 spheres in a periodic box they
//! were 80 % of a PSE step (`docs/PERIODIC.md`).
//!
//! **What it finds.** The spheres in the 27 cells around a position (fewer at the edge
//! of the grid in free space): every sphere whose minimum-image distance (a plain
//! distance without a box) is below the cutoff it was built for, and possibly more.
//! The callers run their own test on each candidate, so a search finds exactly the
//! pairs the all-pairs loop finds; the candidates are a superset by a margin that
//! covers the rounding of the coordinates (`MARGIN` of the cutoff plus
//! `SLACK` epsilons of the largest coordinate). The callers visit the pairs in the
//! all-pairs loop's order (the contacts sort each row's candidates; the overlap check
//! takes the smallest pair), so the bits are those of the all-pairs scan.
//!
//! **Geometry.** In a periodic box the grid covers the box (positions wrapped into
//! it), at least 3 cells per axis so that the 27 neighbours of a cell are distinct
//! cells; a box too small for 3 cells of the cutoff per axis takes every pair. In free
//! space (and above a wall) the grid covers the positions' bounding box. Either way at
//! most `n` cells: a wider grid gets wider cells.
//!
//! **Storage.** `3 n + 1` indices of the caller's workspace ([`indices`], counted by
//! [`Layout`](crate::Layout)): the spheres sorted by cell (counting sort, index order
//! within a cell), the cells' starts, and a row of candidates for the caller. Below
//! [`CELLS_MIN`] spheres, or without the `cells` feature (firmware), none: every pair.

use crate::cell::Periodic;
use crate::real::Real;

mod pairs;
pub use pairs::{PairOrder, check_pairs_in, check_pairs_periodic, first_pair};

/// Spheres from which the pair searches use a cell list; below, every pair is visited.
/// Measured (`examples/pair_search.rs`: a step with contacts on, CPU time): the cell
/// list costs more at 16 spheres (17-19 against 14.5-15 us a step), the same at 32 and
/// 48, less from 64 (46-49 against 51-57 us; at 256, 318-324 against 636-684 us).
pub const CELLS_MIN: usize = 64;

/// Relative widening of the cutoff (rounding of the distances compared).
const MARGIN: f64 = 1.0 / 1024.0;

/// Machine epsilons of the largest coordinate added to the cutoff (rounding of the
/// coordinates' differences and of their cells).
const SLACK: f64 = 64.0;

/// Indices a cell list over `n` spheres takes from the workspace: `3 n + 1` from
/// [`CELLS_MIN`] spheres on with the `cells` feature, else none.
pub const fn indices(n: usize) -> usize {
    if cfg!(feature = "cells") && n >= CELLS_MIN {
        3 * n + 1
    } else {
        0
    }
}

/// The spheres sorted into a grid of cells.
#[derive(Debug)]
pub(crate) struct CellList<'s> {
    /// Cells per axis.
    dims: [usize; 3],
    /// A periodic grid (the box's), else the bounding box's.
    periodic: bool,
    /// Lower corner (free space) or zero (a box).
    origin: [f64; 3],
    /// Box edges (a box) or cell edges (free space, at least the cutoff).
    edge: [f64; 3],
    /// The spheres, cell by cell.
    order: &'s [usize],
    /// `order[start[c]..start[c + 1]]` are the spheres of cell `c`.
    start: &'s [usize],
}

impl<'s> CellList<'s> {
    /// Sorts `pos` into cells at least `cutoff` wide (plus the margins), in the box
    /// `cell` or in free space, with storage from `store` ([`indices`]). Returns the
    /// list and the rest of `store` (`n` indices for the caller's row of candidates),
    /// or `None` where every pair should be visited: below [`CELLS_MIN`] spheres, a
    /// store too small, a cutoff or position that is not finite, a box with fewer than
    /// 3 cells per axis, or a grid that cannot hold `n` cells.
    pub(crate) fn build<T: Real>(
        pos: &[T::V3],
        cell: Option<&Periodic<T>>,
        cutoff: T,
        store: &'s mut [usize],
    ) -> Option<(Self, &'s mut [usize])> {
        let n = pos.len();
        if !cfg!(feature = "cells") || n < CELLS_MIN || store.len() < 3 * n + 1 {
            return None;
        }
        let (lo, hi) = bounds::<T>(pos)?;
        let big = (0..3).fold(0.0f64, |m, d| m.max(lo[d].abs()).max(hi[d].abs()));
        let reach = cutoff.to_f64() * (1.0 + MARGIN) + SLACK * T::EPSILON.to_f64() * big;
        if !(reach.is_finite() && reach > 0.0) {
            return None;
        }
        let periodic = cell.is_some() && cfg!(feature = "periodic");
        // The box's edges, or the bounding box's (its cells at least `reach` wide).
        let span = match cell {
            Some(c) if periodic => c.size().map(|x| x.to_f64()),
            _ => [0, 1, 2].map(|d| hi[d] - lo[d]),
        };
        // As many cells per axis as the cutoff allows (`n` at most), then the most
        // numerous axis halved until there are at most `n` cells (`n >= 27`).
        let mut dims = span.map(|s| libm::floor(s / reach).min(n as f64).max(0.0) as usize);
        if periodic && dims.iter().any(|&k| k < 3) {
            return None;
        }
        let floor = if periodic { 3 } else { 1 };
        dims = dims.map(|k| k.max(floor));
        while dims[0] * dims[1] * dims[2] > n {
            let d = if dims[0] >= dims[1] && dims[0] >= dims[2] {
                0
            } else if dims[1] >= dims[2] {
                1
            } else {
                2
            };
            dims[d] = (dims[d] / 2).max(floor);
        }
        let (origin, edge) = match periodic {
            true => ([0.0; 3], span),
            false => (lo, [0, 1, 2].map(|d| (span[d] / dims[d] as f64).max(reach))),
        };
        let cells = dims[0] * dims[1] * dims[2];
        let (order, rest) = store.split_at_mut(n);
        let (start, rest) = rest.split_at_mut(n + 1);
        let mut list = CellList {
            dims,
            periodic,
            origin,
            edge,
            order: &[],
            start: &[],
        };
        // Counting sort: `start[c + 1]` counts cell `c`, then the cursors.
        start[..=cells].fill(0);
        for &p in pos {
            start[list.linear(list.cell_of::<T>(p)) + 1] += 1;
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        for (j, &p) in pos.iter().enumerate() {
            let c = list.linear(list.cell_of::<T>(p));
            order[start[c]] = j;
            start[c] += 1;
        }
        for c in (1..=cells).rev() {
            start[c] = start[c - 1];
        }
        start[0] = 0;
        list.order = order;
        list.start = &start[..=cells];
        Some((list, &mut rest[..n]))
    }

    /// The cell of a position, per axis (wrapped into the box in a periodic grid).
    #[inline(always)]
    fn cell_of<T: Real>(&self, p: T::V3) -> [usize; 3] {
        let p = T::v3_to_f64(p);
        let mut c = [0; 3];
        for d in 0..3 {
            let u = if self.periodic {
                let q = p[d] / self.edge[d];
                (q - libm::floor(q)) * self.dims[d] as f64
            } else {
                (p[d] - self.origin[d]) / self.edge[d]
            };
            c[d] = (libm::floor(u).max(0.0) as usize).min(self.dims[d] - 1);
        }
        c
    }

    #[inline(always)]
    fn linear(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    /// The neighbouring cells of `c` along axis `d`: `c - 1, c, c + 1` (wrapped in a
    /// box, which has at least 3 cells per axis, so they are distinct; clipped to the
    /// grid in free space).
    #[inline(always)]
    fn axis(&self, c: usize, d: usize) -> ([usize; 3], usize) {
        let n = self.dims[d];
        if self.periodic {
            ([(c + n - 1) % n, c, (c + 1) % n], 3)
        } else {
            let first = c.saturating_sub(1);
            let last = (c + 1).min(n - 1);
            ([first, first + 1, first + 2], last - first + 1)
        }
    }

    /// The spheres cell by cell: an order in which neighbours are near in memory (read by
    /// the fast free-space product alone).
    #[cfg(feature = "fast-free")]
    pub(crate) fn order(&self) -> &[usize] {
        self.order
    }

    /// Calls `f(j)` for every sphere `j` in the cells around `p` (its own included),
    /// each once, in the list's order.
    #[inline]
    pub(crate) fn near<T: Real>(&self, p: T::V3, mut f: impl FnMut(usize)) {
        let c = self.cell_of::<T>(p);
        let (zs, kz) = self.axis(c[2], 2);
        let (ys, ky) = self.axis(c[1], 1);
        let (xs, kx) = self.axis(c[0], 0);
        for &z in &zs[..kz] {
            for &y in &ys[..ky] {
                for &x in &xs[..kx] {
                    let k = self.linear([x, y, z]);
                    for &j in &self.order[self.start[k]..self.start[k + 1]] {
                        f(j);
                    }
                }
            }
        }
    }

    /// The spheres `j < i` around `p`, ascending, written into `row` (the store
    /// [`CellList::build`] returned): the order in which the all-pairs loop
    /// `for j in 0..i` meets the ones it can accept.
    pub(crate) fn below<'r, T: Real>(
        &self,
        i: usize,
        p: T::V3,
        row: &'r mut [usize],
    ) -> &'r [usize] {
        let mut k = 0;
        self.near::<T>(p, |j| {
            if j < i {
                row[k] = j;
                k += 1;
            }
        });
        let row = &mut row[..k];
        row.sort_unstable();
        row
    }
}

/// The positions' bounding box, `None` if one is not finite (or there are none).
fn bounds<T: Real>(pos: &[T::V3]) -> Option<([f64; 3], [f64; 3])> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &p in pos {
        let p = T::v3_to_f64(p);
        for d in 0..3 {
            if !p[d].is_finite() {
                return None;
            }
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    Some((lo, hi))
}

/// The largest radius (zero for none).
pub(crate) fn largest<T: Real>(radius: &[T]) -> T {
    radius.iter().fold(T::ZERO, |m, &a| m.max(a))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small generator (SplitMix64) for the configurations (the pair checks' tests
    /// use it too).
    pub(super) struct Mix(pub(super) u64);
    impl Mix {
        pub(super) fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    const N: usize = 400;

    /// Every pair closer than the cutoff (minimum image in a box) is among the
    /// candidates `below` returns, which are ascending, distinct and below `i`.
    fn covers<T: Real>(pos: &[T::V3], cell: Option<&Periodic<T>>, cutoff: f64) -> bool {
        let mut store = [0usize; 3 * N + 1];
        let Some((list, row)) = CellList::build(pos, cell, T::from_f64(cutoff), &mut store) else {
            return false;
        };
        let mut found = 0;
        for i in 0..pos.len() {
            let near = list.below::<T>(i, pos[i], row);
            assert!(near.windows(2).all(|w| w[0] < w[1]) && near.iter().all(|&j| j < i));
            for j in 0..i {
                let r = crate::cell::image(cell, pos[i] - pos[j]);
                if T::norm(r).to_f64() < cutoff {
                    assert!(near.binary_search(&j).is_ok(), "pair ({i}, {j}) missed");
                    found += 1;
                }
            }
        }
        assert!(
            found > 0,
            "no pair within the cutoff: the test proves nothing"
        );
        true
    }

    fn positions<T: Real>(seed: u64, span: [f64; 3], shift: [f64; 3]) -> [T::V3; N] {
        let mut g = Mix(seed);
        core::array::from_fn(|_| T::v3_from([0, 1, 2].map(|d| g.next() * span[d] + shift[d])))
    }

    fn boxes<T: Real>() -> Result<(), crate::cell::PeriodicError> {
        // Cubic, rectangular and elongated boxes; positions unwrapped by many edges.
        let cases = [
            ([20.0, 20.0, 20.0], [0.0; 3], 2.5),
            ([20.0, 20.0, 20.0], [-140.0, 60.0, 2000.0], 2.5),
            ([60.0, 9.0, 8.0], [0.0; 3], 2.5),
            ([12.0, 12.0, 30.0], [3.0, -7.0, 1.0], 3.9),
        ];
        for (seed, (l, shift, cutoff)) in cases.into_iter().enumerate() {
            let c = Periodic::new(l.map(T::from_f64))?;
            // Positions spread over three boxes per axis: the images matter.
            let pos = positions::<T>(seed as u64, l.map(|x| 3.0 * x), shift);
            assert!(covers::<T>(&pos, Some(&c), cutoff), "{l:?}");
        }
        // Fewer than 3 cells on an axis: every pair instead.
        let c = Periodic::new([T::from_f64(7.0); 3])?;
        let pos = positions::<T>(9, [7.0; 3], [0.0; 3]);
        assert!(!covers::<T>(&pos, Some(&c), 2.5));
        Ok(())
    }

    fn free<T: Real>() {
        // A cube, a flat layer (spheres on a wall), two clusters far apart.
        let mut two = positions::<T>(3, [10.0, 10.0, 10.0], [0.0; 3]);
        for p in two.iter_mut().skip(N / 2) {
            *p += T::v3_from([1e4, -3e3, 50.0]);
        }
        let cases = [
            positions::<T>(1, [30.0, 30.0, 30.0], [-15.0, 4.0, 100.0]),
            positions::<T>(2, [80.0, 80.0, 0.0], [0.0, 0.0, 1.0]),
            two,
        ];
        for pos in cases {
            assert!(covers::<T>(&pos, None, 2.2));
        }
    }

    /// Below the threshold, with too little storage, with a position or a cutoff not
    /// finite: no list (every pair).
    #[test]
    fn refusals() {
        let pos = positions::<f64>(4, [20.0; 3], [0.0; 3]);
        let mut store = [0usize; 3 * N + 1];
        assert!(CellList::build::<f64>(&pos[..CELLS_MIN - 1], None, 2.0, &mut store).is_none());
        assert!(CellList::build::<f64>(&pos, None, 2.0, &mut store[..3 * N]).is_none());
        assert!(CellList::build::<f64>(&pos, None, f64::NAN, &mut store).is_none());
        let mut bad = pos;
        bad[7] = glam::DVec3::new(0.0, f64::NAN, 0.0);
        assert!(CellList::build::<f64>(&bad, None, 2.0, &mut store).is_none());
        assert!(CellList::build::<f64>(&pos, None, 2.0, &mut store).is_some());
    }

    #[test]
    fn finds_every_pair_in_a_box_f64() -> Result<(), crate::cell::PeriodicError> {
        boxes::<f64>()
    }

    #[test]
    fn finds_every_pair_in_a_box_f32() -> Result<(), crate::cell::PeriodicError> {
        boxes::<f32>()
    }

    #[test]
    fn finds_every_pair_in_free_space_f64() {
        free::<f64>();
    }

    #[test]
    fn finds_every_pair_in_free_space_f32() {
        free::<f32>();
    }
}
