//! The third stage of a step: accepting the candidate state before it is committed
//! (finite, clear of the place's hard surfaces, no nested or, unless allowed,
//! overlapping spheres). Apart from the input checks because it is a pair search: in
//! the mobility's bands through the host's threads, over every pair or a cell list's
//! neighbours, with the same answer on any number of threads.

use crate::cell::image;
use crate::cell_list::CellList;
use crate::error::{ParticleError, StepError};
use crate::integrate::stages::cell;
use crate::parallel::{BANDS, Parallel, band_start, bands, map_bands};
use crate::params::Params;
use crate::real::Real;

/// Finite, no nested spheres, no overlap unless allowed (squared distances: no sqrt;
/// the minimum image in a periodic box), no sphere below the wall. With contacts, spheres touch to within the solver's
/// tolerance, which is accepted; so do spheres on the wall. The pair check
/// runs in the mobility's bands through `par` (it was the step's largest serial part,
/// ~4 % at N = 4096 on one thread) and reports the pair a single pass in order meets
/// first, on any number of threads: over every pair, or from
/// [`CELLS_MIN`](crate::cell_list::CELLS_MIN) spheres on over the neighbours a cell list
/// in `cells` finds ([`crate::cell_list`], cells as wide as the largest contact
/// distance), which is the same pair.
pub(in crate::integrate) fn accept<T: Real>(
    pos: &[T::V3],
    vel: &[T::V3],
    omega: &[T::V3],
    radius: &[T],
    p: &Params<T>,
    par: &dyn Parallel,
    cells: &mut [usize],
) -> Result<(), StepError> {
    for i in 0..pos.len() {
        if !(T::v3_is_finite(pos[i]) && T::v3_is_finite(vel[i]) && T::v3_is_finite(omega[i])) {
            return Err(StepError::NonFinite { particle: i });
        }
    }
    // No sphere past a hard surface of the place (the wall's plane).
    for s in p.place().surfaces().iter() {
        if let Some(particle) = s.first_crossed(pos, radius, p.solver.tolerance) {
            return Err(ParticleError::BelowWall { particle }.into());
        }
    }
    if p.place().cell().is_some()
        && let Some(particle) = super::periodic_box::unresolved(pos, radius)
    {
        return Err(ParticleError::Unresolved { particle }.into());
    }
    let n = pos.len();
    // Without the `cells` feature (firmware) this is the all-pairs check alone.
    let list = if cfg!(feature = "cells") && n >= crate::cell_list::CELLS_MIN {
        let cutoff = crate::cell_list::largest(radius) * T::TWO;
        CellList::build(pos, cell(p).as_ref(), cutoff, cells)
    } else {
        None
    };
    let first = if let Some((list, _)) = list {
        let rows = |t: usize| n * t / BANDS..n * (t + 1) / BANDS;
        match bands(n) {
            1 => first_near(pos, radius, p, &list, 0..n),
            _ => map_bands(par, n, |t| first_near(pos, radius, p, &list, rows(t)))
                .into_iter()
                .flatten()
                .flatten()
                .min(),
        }
    } else if bands(n) == 1 {
        first_clash(pos, radius, p, 0..n)
    } else {
        // Each band's first pair in the order `(i, j)`, `i < j`, then the first of those.
        let found = map_bands(par, n, |t| {
            first_clash(pos, radius, p, band_start(n, t)..band_start(n, t + 1))
        });
        found.into_iter().flatten().flatten().min()
    };
    match first {
        Some((i, j)) => Err(StepError::Overlap { i, j }),
        None => Ok(()),
    }
}

/// The first pair `(i, j)`, `i < j`, in that order, of nested (or, unless allowed,
/// overlapping) spheres among the pairs whose later sphere `j` is in `rows`.
fn first_clash<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    p: &Params<T>,
    rows: core::ops::Range<usize>,
) -> Option<(usize, usize)> {
    let allow_overlap = p.allow_overlap;
    let cell = cell(p);
    let reach = match p.contacts {
        Some(_) => T::ONE - p.solver.tolerance * T::TWO,
        None => T::ONE,
    };
    let mut first: Option<(usize, usize)> = None;
    for j in rows {
        let (pj, aj) = (pos[j], radius[j]);
        // A later row can only improve on `first` with a smaller `i`.
        let end = first.map_or(j, |(i, _)| i.min(j));
        for (i, (&pi, &ai)) in pos[..end].iter().zip(radius).enumerate() {
            let s2 = T::norm2(image(cell.as_ref(), pi - pj));
            let (dif, sum) = (ai - aj, (ai + aj) * reach);
            if s2 <= dif * dif || (!allow_overlap && s2 < sum * sum) {
                first = Some((i, j));
                break;
            }
        }
    }
    first
}

/// [`first_clash`] over the cell list's neighbours (the same test, kept beside the
/// all-pairs loop rather than shared so that firmware's code stays as it was): the
/// first pair `(i, j)`, `i < j`, whose earlier sphere `i` is in `rows` (the smallest
/// `i` with a clash, then its smallest `j`).
fn first_near<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    p: &Params<T>,
    list: &CellList<'_>,
    rows: core::ops::Range<usize>,
) -> Option<(usize, usize)> {
    let (allow_overlap, cell) = (p.allow_overlap, cell(p));
    let reach = match p.contacts {
        Some(_) => T::ONE - p.solver.tolerance * T::TWO,
        None => T::ONE,
    };
    let clashes = |(pi, ai): (T::V3, T), (pj, aj): (T::V3, T)| {
        let s2 = T::norm2(image(cell.as_ref(), pi - pj));
        let (dif, sum) = (ai - aj, (ai + aj) * reach);
        s2 <= dif * dif || (!allow_overlap && s2 < sum * sum)
    };
    for i in rows {
        let mut first: Option<usize> = None;
        let (pi, ai) = (pos[i], radius[i]);
        list.near::<T>(pi, |j| {
            let later = j > i && first.is_none_or(|f| j < f);
            if later && clashes((pi, ai), (pos[j], radius[j])) {
                first = Some(j);
            }
        });
        if let Some(j) = first {
            return Some((i, j));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::Serial;
    use glam::DVec3;

    /// The banded pair check (600 spheres: 16 bands) reports the pair a single pass in
    /// the order `(i, j)`, `i < j`, meets first (a brute-force loop here), also when a
    /// later band holds it and an earlier band holds another; with and without the cell
    /// list, in free space and in a box.
    #[test]
    fn banded_check_reports_the_first_pair_in_order() -> Result<(), crate::cell::PeriodicError> {
        const N: usize = 600;
        assert!(bands(N) > 1);
        let line: [DVec3; N] = core::array::from_fn(|k| DVec3::new(3.0 * k as f64, 0.0, 0.0));
        let (radius, zero) = ([1.0; N], [DVec3::ZERO; N]);
        let p = Params::<f64>::new(0.01);
        // A box long enough that no image comes near (the line is 1800 long).
        let boxed = crate::cell::Periodic::new([4000.0, 17.0, 17.0])?;
        let first = |pos: &[DVec3]| {
            (0..N)
                .flat_map(|i| (i + 1..N).map(move |j| (i, j)))
                .find(|&(i, j)| (pos[i] - pos[j]).length_squared() < 4.0)
        };
        let cases: [&[(usize, usize)]; 5] = [
            &[],
            &[(300, 200)],
            &[(300, 200), (590, 10)],
            &[(590, 10), (599, 10)],
            &[(599, 11), (598, 10), (40, 30)],
        ];
        for moves in cases {
            let mut pos = line;
            for &(m, to) in moves {
                pos[m] = line[to] + DVec3::new(0.0, 1.5, 0.0);
            }
            let want = first(&pos).map_or(Ok(()), |(i, j)| Err(StepError::Overlap { i, j }));
            // With a cell list (free space, and a box of 8 cells per axis), and
            // without one (no storage: every pair).
            let mut cells = [0; 3 * N + 1];
            for q in [
                p,
                Params {
                    periodic: Some(boxed),
                    ..p
                },
            ] {
                for store in [&mut cells[..], &mut []] {
                    let got = accept(&pos, &zero, &zero, &radius, &q, &Serial, store);
                    assert_eq!(got, want, "{moves:?}");
                }
            }
        }
        Ok(())
    }
}
