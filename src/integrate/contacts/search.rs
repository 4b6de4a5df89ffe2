//! The contact search: the pairs that end overlapping or crossed within the step (every
//! pair, or a cell list's candidates in the same order), the spheres that reach the
//! wall, and the pool of one-sided constraints they are pushed into ([`Active`]), with
//! the anti-cycling memory of the releases.

use crate::bonds::Bond;
use crate::cell::{Periodic, image};
use crate::cell_list::{self, CellList};
use crate::error::StepError;
use crate::real::Real;

/// Appends a wall link for every sphere whose centre is closer than `reach` times its
/// radius to the plane `z = height` (or below it) and has none yet; returns how many
/// were added. With `ceiling`, ceiling links for the spheres that near the plane from
/// below ([`Bond::ceiling`]).
pub(super) fn add_wall<T: Real>(
    pos: &[T::V3],
    (height, ceiling): (T, bool),
    radius: &[T],
    reach: T,
    set: &mut Active<'_, T>,
) -> Result<usize, StepError> {
    let mut added = 0;
    for (i, (&r, &a)) in pos.iter().zip(radius).enumerate() {
        let z = T::xyz(r)[2];
        let gap = match ceiling {
            true => height - z,
            false => z - height,
        };
        if !(gap < a * reach) {
            continue;
        }
        let held = |l: &Bond<T>| l.is_wall() && l.i == i && l.is_ceiling() == ceiling;
        if set.held().iter().any(held) {
            continue;
        }
        set.push(match ceiling {
            true => Bond::ceiling(i, a),
            false => Bond::wall(i, a),
        })?;
        added += 1;
    }
    Ok(added)
}

/// The one-sided constraints of a step in the link storage: `nc` active ones after
/// the `nb` bonds, and at the pool's far end the `released` ones (latest last from the
/// end) that the anti-cycling rule remembers.
pub(super) struct Active<'s, T: Real> {
    nb: usize,
    pool: usize,
    links: &'s mut [Bond<T>],
    nc: &'s mut usize,
    released: &'s mut usize,
}

impl<'s, T: Real> Active<'s, T> {
    pub(super) fn new(
        nb: usize,
        pool: usize,
        links: &'s mut [Bond<T>],
        nc: &'s mut usize,
        released: &'s mut usize,
    ) -> Self {
        Self {
            nb,
            pool,
            links,
            nc,
            released,
        }
    }

    /// The active one-sided constraints.
    fn held(&self) -> &[Bond<T>] {
        &self.links[self.nb..self.nb + *self.nc]
    }

    /// The released ones remembered.
    fn remembered(&self) -> &[Bond<T>] {
        let end = self.nb + self.pool;
        &self.links[end - *self.released..end]
    }

    /// Appends `link`, unless the pool is full; forgets the oldest release to make
    /// room.
    fn push(&mut self, link: Bond<T>) -> Result<(), StepError> {
        if *self.nc == self.pool {
            return Err(StepError::ContactsFull {
                capacity: self.pool,
            });
        }
        if *self.nc + *self.released == self.pool {
            *self.released -= 1;
        }
        self.links[self.nb + *self.nc] = link;
        *self.nc += 1;
        Ok(())
    }

    /// Releases the contact whose multiplier pulls hardest (negative: a contact pushes
    /// along `r_i - r_j` with a positive multiplier), keeping the others in order;
    /// a contact released once in this step is held (anti-cycling). Returns its row
    /// (the bonds' and active ones' index) where one was released.
    pub(super) fn release_pulling(&mut self, lambda: &[T]) -> Option<usize> {
        let (nb, nc) = (self.nb, *self.nc);
        let mut worst: Option<(usize, T)> = None;
        for (k, link) in self.held().iter().enumerate() {
            let l = lambda[nb + k];
            let again = self.remembered().iter().any(|r| same(r, link));
            if l < T::ZERO && !again && worst.is_none_or(|(_, w)| l < w) {
                worst = Some((k, l));
            }
        }
        let (k, _) = worst?;
        let link = self.links[nb + k];
        self.links.copy_within(nb + k + 1..nb + nc, nb + k);
        *self.nc -= 1;
        // Remember it: the slot freed at the end of the active ones is at most the
        // one written here.
        let end = nb + self.pool;
        if *self.released < self.pool - *self.nc {
            *self.released += 1;
        }
        let slot = end - *self.released;
        self.links.copy_within(slot + 1..end, slot);
        self.links[end - 1] = link;
        Some(nb + k)
    }
}

/// Whether two links hold the same constraint (the same pair, or the same sphere's
/// wall link).
fn same<T: Real>(a: &Bond<T>, b: &Bond<T>) -> bool {
    a.is_wall() == b.is_wall()
        && a.is_ceiling() == b.is_ceiling()
        && ((a.i == b.i && a.j == b.j) || (!a.is_wall() && a.i == b.j && a.j == b.i))
}

/// Appends every unbonded pair that ends closer than `reach` times its contact distance
/// or crossed within it on the straight path from `from` to `to`, and is not yet a
/// contact; returns how many were added. In a periodic box the path starts at the
/// minimum image of the pair's separation and moves with the pair's relative
/// displacement (the image is not taken again at its end, where a pair near half the
/// box apart would jump across the box and seem to pass through contact); the end
/// is compared by its minimum image.
///
/// The pairs are visited in the order `i` ascending, then `j < i` ascending: every
/// pair, or from [`cell_list::CELLS_MIN`] spheres on the candidates of a cell list
/// (`cells`, [`cell_list::indices`]) over the end positions with cells as wide as the
/// largest contact distance within `reach` plus twice the largest displacement (a
/// pair whose path comes within contact ends no farther apart than that), sorted
/// into the same order: the same pairs, pushed in the same order, the same bits.
pub(super) fn add_pairs<T: Real>(
    bonds: &[Bond<T>],
    (from, to): (&[T::V3], &[T::V3]),
    radius: &[T],
    cell: Option<Periodic<T>>,
    reach: T,
    set: &mut Active<'_, T>,
    cells: &mut [usize],
) -> Result<usize, StepError> {
    let mut added = 0;
    let mut pair = |i: usize, j: usize| -> Result<(), StepError> {
        let sigma = radius[i] + radius[j];
        let far = sigma * reach;
        let (d0, d1) = match cell {
            Some(c) if cfg!(feature = "periodic") => {
                let d0 = c.minimum_image(from[i] - from[j]);
                (d0, d0 + ((to[i] - from[i]) - (to[j] - from[j])))
            }
            _ => (from[i] - from[j], to[i] - to[j]),
        };
        let ends = T::norm2(image(cell.as_ref(), d1)) < far * far;
        let crossed = !(T::dot(d0, d1) > T::ZERO) && closest2::<T>(d0, d1) < far * far;
        if !(ends || crossed) {
            return Ok(());
        }
        let joins = |b: &Bond<T>| (b.i == i && b.j == j) || (b.i == j && b.j == i);
        // Two pinned spheres cannot move apart: no contact between them.
        let pinned = |s| bonds.iter().any(|b| b.is_pin() && b.i == s);
        if bonds.iter().any(joins) || set.held().iter().any(joins) || pinned(i) && pinned(j) {
            return Ok(());
        }
        set.push(Bond {
            i,
            j,
            length: sigma,
        })?;
        added += 1;
        Ok(())
    };
    let list = if to.len() >= cell_list::CELLS_MIN {
        let moved = from
            .iter()
            .zip(to)
            .fold(T::ZERO, |m, (&a, &b)| m.max(T::norm2(b - a)));
        let contact = cell_list::largest(radius) * T::TWO * reach.max(T::ONE);
        CellList::build(to, cell.as_ref(), contact + moved.sqrt() * T::TWO, cells)
    } else {
        None
    };
    match list {
        Some((list, row)) => {
            for i in 0..to.len() {
                for &j in list.below::<T>(i, to[i], row) {
                    pair(i, j)?;
                }
            }
        }
        None => {
            for i in 0..to.len() {
                for j in 0..i {
                    pair(i, j)?;
                }
            }
        }
    }
    Ok(added)
}

/// Smallest squared length of `d0 + t (d1 - d0)` for `t` in `[0, 1]`.
fn closest2<T: Real>(d0: T::V3, d1: T::V3) -> T {
    let e = d1 - d0;
    let ee = T::norm2(e);
    let t = if ee > T::ZERO {
        (-T::dot(d0, e) / ee).max(T::ZERO).min(T::ONE)
    } else {
        T::ZERO
    };
    T::norm2(d0 + e * t)
}
