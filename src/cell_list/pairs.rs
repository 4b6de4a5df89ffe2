//! The first pair of spheres that fails a test, in a fixed order, over a cell list's
//! candidates: the start-up checks (nested, coincident or overlapping spheres) in
//! `O(N)` instead of visiting every pair, with the all-pairs loop's answer.

use super::CellList;
use crate::cell::Periodic;
use crate::fault::ParticleError;
use crate::real::Real;

/// The order in which the pairs `(i, j)`, `i < j`, are met: which failing pair is the
/// first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairOrder {
    /// The smallest `i`, then its smallest `j` (`for i { for j in i + 1.. }`).
    EarlierFirst,
    /// The smallest `j`, then its smallest `i` (`for j { for i in 0..j }`).
    LaterFirst,
}

/// The first pair `(i, j)`, `i < j`, in `order`, for which `test(i, j)` holds: the
/// pair the all-pairs loop in that order returns, provided every pair that passes
/// `test` is closer than `cutoff` (through the minimum image of `cell`, plainly
/// without one). From [`CELLS_MIN`](super::CELLS_MIN) spheres on, with the `cells`
/// feature and [`indices`](super::indices)`(n)` indices in `store`, only the cell
/// list's candidates are tested (`O(N)` pairs for spheres spread in space); otherwise,
/// or where no list can be built (a position or the cutoff not finite, a box with
/// fewer than three cells per axis), every pair.
pub fn first_pair<T: Real>(
    pos: &[T::V3],
    cell: Option<&Periodic<T>>,
    cutoff: T,
    order: PairOrder,
    store: &mut [usize],
    mut test: impl FnMut(usize, usize) -> bool,
) -> Option<(usize, usize)> {
    let n = pos.len();
    let pair = |k: usize, m: usize| if k < m { (k, m) } else { (m, k) };
    let later = order == PairOrder::LaterFirst;
    let Some((list, _)) = CellList::build(pos, cell, cutoff, store) else {
        // Every pair: for each sphere `k` in turn, its partners `m` ascending.
        for k in 0..n {
            let partners = if later { 0..k } else { k + 1..n };
            for m in partners {
                if test(pair(k, m).0, pair(k, m).1) {
                    return Some(pair(k, m));
                }
            }
        }
        return None;
    };
    for (k, &p) in pos.iter().enumerate() {
        let mut first: Option<usize> = None;
        list.near::<T>(p, |m| {
            let partner = if later { m < k } else { m > k };
            if partner && first.is_none_or(|f| m < f) && test(pair(k, m).0, pair(k, m).1) {
                first = Some(m);
            }
        });
        if let Some(m) = first {
            return Some(pair(k, m));
        }
    }
    None
}

/// [`check_pairs`](crate::particles::check_pairs) over a cell list in `store`
/// ([`indices`](super::indices)`(n)` indices; fewer: every pair): the same error for
/// the same pair, since only spheres closer than twice the largest radius can be
/// nested or overlap. Fixed order (`i` ascending, then `j`).
pub fn check_pairs_in<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    allow_overlap: bool,
    store: &mut [usize],
) -> Result<(), ParticleError> {
    check_pairs_periodic(pos, radius, allow_overlap, None, store)
}

/// [`check_pairs_in`] in the periodic box `cell` when given: each pair through the
/// minimum image, so spheres that overlap through a face are refused as the step
/// would refuse them.
pub fn check_pairs_periodic<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    allow_overlap: bool,
    cell: Option<&Periodic<T>>,
    store: &mut [usize],
) -> Result<(), ParticleError> {
    let n = pos.len().min(radius.len());
    let (pos, radius) = (&pos[..n], &radius[..n]);
    let verdict = |i: usize, j: usize| {
        let s = T::norm(crate::cell::image(cell, pos[i] - pos[j]));
        let (ai, aj) = (radius[i], radius[j]);
        if s == T::ZERO {
            Some(ParticleError::Coincident { i, j })
        } else if s <= (ai - aj).abs() {
            Some(ParticleError::Nested { i, j })
        } else if !allow_overlap && s < ai + aj {
            Some(ParticleError::Overlap { i, j })
        } else {
            None
        }
    };
    // Both tests need `s <= |a_i| + |a_j|` (signed radii included).
    let cutoff = radius.iter().fold(T::ZERO, |m, &a| m.max(a.abs())) * T::TWO;
    let found = first_pair(pos, cell, cutoff, PairOrder::EarlierFirst, store, |i, j| {
        verdict(i, j).is_some()
    });
    match found.and_then(|(i, j)| verdict(i, j)) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cell::PeriodicError;
    use glam::DVec3;

    use crate::cell_list::tests::Mix;

    /// The all-pairs loop in `order`, written out here.
    fn brute(
        n: usize,
        order: PairOrder,
        test: impl Fn(usize, usize) -> bool,
    ) -> Option<(usize, usize)> {
        let pairs = (0..n).flat_map(|a| (a + 1..n).map(move |b| (a, b)));
        match order {
            PairOrder::EarlierFirst => pairs.filter(|&(i, j)| test(i, j)).min(),
            PairOrder::LaterFirst => pairs
                .filter(|&(i, j)| test(i, j))
                .min_by_key(|&(i, j)| (j, i)),
        }
    }

    /// Random configurations (dilute to crowded, radii 0.2 to 1.5, nested and
    /// coincident spheres planted in some), in free space and in boxes with positions
    /// unwrapped by several edges: the cell list's first pair is the all-pairs loop's,
    /// in both orders, for the nested-only and the overlap verdicts, and
    /// `check_pairs_in` gives `check_pairs`' error.
    #[test]
    fn the_cell_list_agrees_with_every_pair() -> Result<(), PeriodicError> {
        let mut g = Mix(11);
        let (mut clashes, mut clean) = (0, 0);
        for case in 0..120 {
            let n = [64, 100, 257][case % 3];
            let spread = [4.0, 8.0, 14.0, 30.0][case % 4];
            let mut pos: [DVec3; 257] = [DVec3::ZERO; 257];
            let mut radius = [0.0; 257];
            for k in 0..n {
                pos[k] = DVec3::new(g.next(), g.next(), g.next()) * spread;
                radius[k] = 0.2 + 1.3 * g.next();
            }
            if case % 5 == 1 {
                // A small sphere inside a large one, late in the list.
                pos[n - 3] = pos[n / 2] + DVec3::new(0.1, 0.0, 0.0);
                radius[n / 2] = 1.5;
                radius[n - 3] = 0.3;
            }
            if case % 7 == 2 {
                pos[n - 1] = pos[n - 2];
            }
            let (pos, radius) = (&pos[..n], &radius[..n]);
            let boxed = Periodic::new([spread / 2.0, spread / 1.5, spread])?;
            let cells = [None, Some(&boxed)];
            for (c, allow) in [(0, false), (0, true), (1, false), (1, true)] {
                let cell = cells[c];
                let test = |i: usize, j: usize| {
                    let s = crate::cell::image(cell, pos[i] - pos[j]).length();
                    s <= (radius[i] - radius[j]).abs() || (!allow && s < radius[i] + radius[j])
                };
                for order in [PairOrder::EarlierFirst, PairOrder::LaterFirst] {
                    let want = brute(n, order, test);
                    let mut store = [0; 3 * 257 + 1];
                    let got = first_pair(pos, cell, 3.0, order, &mut store, test);
                    assert_eq!(got, want, "case {case}, box {c}, {order:?}");
                    match want {
                        Some(_) => clashes += 1,
                        None => clean += 1,
                    }
                }
            }
            let mut store = [0; 3 * 257 + 1];
            for allow in [false, true] {
                let want = check_pairs_in(pos, radius, allow, &mut []);
                assert_eq!(check_pairs_in(pos, radius, allow, &mut store), want);
            }
        }
        assert!(clashes > 50 && clean > 50, "{clashes} / {clean}");
        Ok(())
    }

    /// At 4000 spheres spread in space the cell list tests a few dozen pairs per
    /// sphere, not the 8 million of every pair.
    #[test]
    fn the_start_checks_visit_o_n_pairs() {
        const N: usize = 4000;
        let mut g = Mix(5);
        let pos: [DVec3; N] =
            core::array::from_fn(|_| DVec3::new(g.next(), g.next(), g.next()) * 60.0);
        let mut store = [0; 3 * N + 1];
        let mut tested = 0usize;
        let found = first_pair(
            &pos,
            None,
            0.4,
            PairOrder::EarlierFirst,
            &mut store,
            |i, j| {
                tested += 1;
                (pos[i] - pos[j]).length() < 0.01
            },
        );
        assert_eq!(found, None);
        assert!(tested < 40 * N, "{tested} pairs tested");
    }
}
