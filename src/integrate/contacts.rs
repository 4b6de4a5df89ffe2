//! The overdamped position projection, and the hard-sphere contacts it holds as
//! one-sided constraints ([`Params::contacts`]).
//!
//! A contact is a link `(i, j)` of length `a_i + a_j` solved with the bonds, through the
//! same metric (the start-of-step mobility) and the same solver. Which pairs are in
//! contact is found by an active-set iteration on the projection's KKT conditions:
//!
//! 1. start from the pairs touching at the start of the step (the last step's contacts,
//!    which it left at contact distance);
//! 2. project the unconstrained move onto the bonds and the active contacts;
//! 3. add every pair that overlaps at the end, or that crossed (its straight path from
//!    the start came within contact and the pair turned by more than a right angle: one
//!    sphere passed through the other within the step); if none does,
//!    release the contact whose multiplier pulls hardest (a contact can only push),
//!    one per round;
//! 4. repeat until nothing changes: every active contact pushes, no other pair overlaps.
//!
//! **Anti-cycling.** A contact released in a step is remembered (at the far end of the
//! pool, past the active ones); if it has to be added again it is *held*: never
//! released again in this step, even if its multiplier pulls (it then pulls for one
//! step, at contact distance; the next step starts from it and may release it). So
//! each pair is released at most once and added at most twice per step, and the
//! rounds are bounded by `3 x pool + 1` whatever the multipliers do — with dependent
//! constraints they are not unique (`docs/CONTACTS.md`), so the one that looks like it
//! pulls may be the wrong one to release. A full pool forgets the oldest release.
//!
//! Each round projects from the unconstrained move again, so the result does not
//! depend on the path. No stiffness: the contacts do not limit `dt`. A step so large
//! that a pair would end in contact on the far side of where it started is refused
//! ([`StepError::Degenerate`], indexed past the bonds), as a bond turned too far is.
//!
//! **The wall** ([`Params::wall`]) takes part in the same iteration: a sphere whose
//! centre would end below `height + a_i` gets a wall link ([`Bond::wall`]: the linear
//! constraint `z_i = height + a_i`, pushing on that sphere alone along `+z`), released
//! like a contact when its multiplier would pull the sphere down. The projection runs in
//! the wall's frame: the candidate is moved by `-height` along `z` before each solve and
//! back at the end (exact for `height = 0`; otherwise the candidate's `z` is rounded
//! twice). With or without [`Params::contacts`]; with a wall, the pool of one-sided
//! constraints holds one wall link per sphere beside the contacts' capacity
//! ([`Params::constraints`]).

use super::{Sums, bond_vectors, mobility_metric, project_positions};
use crate::bonds::Bond;
use crate::cell::{Periodic, image};
use crate::cell_list::{self, CellList};
use crate::constraints::{Scratch, SolveStats};
use crate::error::{Row, Stage, StepError};
use crate::linalg::Mob;
use crate::params::{Contacts, Params};
use crate::real::Real;
use crate::workspace::Links;

/// The slices the overdamped position projection works in.
pub(super) struct Projection<'l, 'v, 'a, T: Real> {
    pub links: Links<'l, T>,
    pub grad: &'v mut [T::V3],
    pub disp: &'v mut [T::V3],
    pub lambda: &'v mut [T],
    pub scratch: &'v mut Scratch<'a, T>,
    /// The step's Ewald parameters in a box ([`super::stages::Sums`]).
    pub ewald: super::stages::Sums<'v, T>,
    /// The compact copy of the mobility the constraint products read
    /// ([`Params::compact_products`]); empty: they read the mobility.
    pub compact: &'v [T::M3],
}

/// What the overdamped position projection did.
pub(super) struct Projected<'l, T: Real> {
    /// The solve (of the last active-set round with contacts).
    pub stats: SolveStats<T>,
    /// The constraints held: the bonds, then the contacts (rows of `grad`, `lambda`).
    pub held: &'l [Bond<T>],
    /// Contacts held (0 without contacts).
    pub contacts: u32,
    /// Wall links held (0 without a wall).
    pub wall_contacts: u32,
    /// Active-set rounds (0 without contacts).
    pub rounds: u32,
}

/// One round's projection ([`Along::project`]): `x` onto `rows` (the bonds, then from
/// `nb` on the one-sided rows) along the step's metric at `start`, `grad` the rows'
/// vectors there; the multipliers from zero into `lambda` ([`project_positions`]).
pub(super) struct Round<'r, 's, T: Real> {
    pub rows: &'r [Bond<T>],
    pub grad: &'r [T::V3],
    pub x: &'r mut [T::V3],
    pub lambda: &'r mut [T],
    pub scratch: &'r mut Scratch<'s, T>,
    pub nb: usize,
    pub start: &'r [T::V3],
}

/// Who solves a round's projection ([`project_along`]): [`Stored`] along the step's
/// mobility, or the iterative near field along `M_SD`'s products
/// (`near_iter/constrained.rs`), which has no stored blocks to read.
pub(super) trait Along<T: Real> {
    /// Solves the round `r` with the step's parameters `p`.
    fn project(&mut self, p: &Params<T>, r: Round<'_, '_, T>) -> Result<SolveStats<T>, StepError>;
}

/// Along the mobility at the start as the step holds it (stored, or matrix-free):
/// [`mobility_metric`] and the step's solver.
struct Stored<'v, T: Real> {
    ewald: Sums<'v, T>,
    radius: &'v [T],
    mu: Mob<'v, T>,
    disp: &'v mut [T::V3],
    compact: &'v [T::M3],
}

impl<T: Real> Along<T> for Stored<'_, T> {
    #[inline(always)]
    fn project(&mut self, p: &Params<T>, r: Round<'_, '_, T>) -> Result<SolveStats<T>, StepError> {
        let (par, ew, radius, mu) = (r.scratch.par, self.ewald, self.radius, self.mu);
        let (disp, compact) = (&mut *self.disp, self.compact);
        let (rows, start, with) = (r.rows, r.start, (par, compact));
        let metric = mobility_metric(p, ew, rows, start, radius, mu, r.grad, p.dt, disp, with);
        project_positions(p, rows, &metric, r.x, r.lambda, r.scratch, r.nb, start)
    }
}

/// The overdamped position projection along the mobility at `start` (`mu`, scaled by
/// `dt`): `free` writes the unconstrained move into `x` (once per round), which is then
/// projected onto the bonds, or onto the bonds and the hard-sphere contacts when
/// [`Params::contacts`] is on ([`project_along`] with [`Stored`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn project_overdamped<'l, T: Real>(
    p: &Params<T>,
    bonds: &'l [Bond<T>],
    start: &[T::V3],
    radius: &[T],
    mu: Mob<'_, T>,
    v: Projection<'l, '_, '_, T>,
    x: &mut [T::V3],
    free: impl Fn(&mut [T::V3]),
) -> Result<Projected<'l, T>, StepError> {
    let Projection {
        links,
        grad,
        disp,
        lambda,
        scratch,
        ewald,
        compact,
    } = v;
    let mut along = Stored {
        ewald,
        radius,
        mu,
        disp,
        compact,
    };
    let rows = (links, grad, lambda, scratch);
    project_along(p, bonds, (start, radius), rows, x, free, &mut along)
}

/// The position projection of [`project_overdamped`], each round solved by `along`.
///
/// Without contacts this is one round over the caller's bonds. Both cases share the
/// one call of the constraint solve: a second call site would stop the compiler from
/// inlining it where the parameters are a constant (firmware), and every solver would
/// be linked.
#[allow(clippy::type_complexity)]
pub(super) fn project_along<'l, T: Real, A: Along<T>>(
    p: &Params<T>,
    bonds: &'l [Bond<T>],
    (start, radius): (&[T::V3], &[T]),
    (links, grad, lambda, scratch): (Links<'l, T>, &mut [T::V3], &mut [T], &mut Scratch<'_, T>),
    x: &mut [T::V3],
    free: impl Fn(&mut [T::V3]),
    along: &mut A,
) -> Result<Projected<'l, T>, StepError> {
    let (links, cells) = links.split();
    // Constants without the `contacts` feature: the one-sided path folds away.
    let contacts = p.contacts.filter(|_| cfg!(feature = "contacts"));
    // The floor the wall links hold, as the geometry answers its hard surfaces
    // (`Place::surfaces`: the wall's plane).
    let wall = p
        .place()
        .surfaces()
        .floor()
        .filter(|_| cfg!(feature = "contacts"));
    let nb = bonds.len();
    let cell = super::cell(p);
    // The pool of one-sided constraints: the contacts' capacity, one wall link per
    // sphere ([`Params::constraints`]).
    let pool = p.constraints(start.len(), nb) - nb;
    let one_sided = match (contacts, wall) {
        (None, None) => None,
        (c, _) => Some(c.unwrap_or(Contacts::new(0))),
    };
    let tol = p.solver.tolerance;
    let mut nc = 0;
    // Contacts released in this step, at the pool's far end (anti-cycling).
    let mut released = 0;
    if one_sided.is_some() {
        links[..nb].copy_from_slice(bonds);
        // The last step's contacts end within the tolerance of touching.
        let reach = T::ONE + tol * T::TWO;
        if contacts.is_some() {
            let mut set = Active::new(nb, pool, links, &mut nc, &mut released);
            add_pairs(bonds, (start, start), radius, cell, reach, &mut set, cells)?;
        }
        if let Some(h) = wall {
            let mut set = Active::new(nb, pool, links, &mut nc, &mut released);
            add_wall(start, h, radius, reach, &mut set)?;
        }
    }
    let mut round = 0;
    // Factorisations of every round's solve.
    let mut factorizations = 0;
    // Newton's factor is carried from round to round (the same chord matrix: the same
    // start, metric and rows), never into a step.
    scratch.carry = Default::default();
    loop {
        round += 1;
        let active = match one_sided {
            Some(_) => &links[..nb + nc],
            None => bonds,
        };
        bond_vectors(active, start, super::cell(p), grad);
        free(x);
        shift(x, wall, -T::ONE);
        // Contacts and wall links are inequalities inside the solve (`docs/CONTACTS.md`).
        let this = Round {
            rows: active,
            grad: &*grad,
            x: &mut *x,
            lambda: &mut *lambda,
            scratch: &mut *scratch,
            nb,
            start,
        };
        let stats = along
            .project(p, this)
            .map_err(|e| too_long(e, active, nb, start, wall, p))?;
        factorizations += stats.factorizations;
        let stats = SolveStats {
            factorizations,
            ..stats
        };
        let Some(c) = one_sided else {
            return Ok(Projected {
                stats,
                held: bonds,
                contacts: 0,
                wall_contacts: 0,
                rounds: 0,
            });
        };
        let reach = T::ONE - tol;
        let mut added = 0;
        let mut set = Active::new(nb, pool, links, &mut nc, &mut released);
        if contacts.is_some() {
            added += add_pairs(bonds, (start, x), radius, cell, reach, &mut set, cells)?;
        }
        if wall.is_some() {
            added += add_wall(x, T::ZERO, radius, reach, &mut set)?;
        }
        let let_go = match added {
            0 => set.release_pulling(lambda),
            _ => None,
        };
        scratch.carry.keep = true;
        scratch.carry.released = let_go;
        if added == 0 && let_go.is_none() {
            // Every contact must end on the side it started from (a sphere above the
            // wall: `grad = (0, 0, a)`, its relative vector `(0, 0, z)`).
            for (k, l) in links[nb..nb + nc].iter().enumerate() {
                if !(T::dot(l.separation(x, cell.as_ref()), grad[nb + k]) > T::ZERO) {
                    return Err(StepError::Degenerate {
                        bond: nb + k,
                        row: Row::of(links, nb + k, nb),
                    });
                }
            }
            shift(x, wall, T::ONE);
            // The rows the solve let go (zero multipliers: apart, or dependent and
            // unloaded) are not held.
            let mut kept = 0;
            for k in nb..nb + nc {
                if lambda[k] != T::ZERO {
                    links[nb + kept] = links[k];
                    grad[nb + kept] = grad[k];
                    lambda[nb + kept] = lambda[k];
                    kept += 1;
                }
            }
            nc = kept;
            let links: &'l [Bond<T>] = links;
            let held = &links[..nb + nc];
            let walls = held.iter().filter(|l| l.is_wall()).count();
            return Ok(Projected {
                stats,
                held,
                contacts: (nc - walls) as u32,
                wall_contacts: walls as u32,
                rounds: round,
            });
        }
        if round >= c.max_rounds {
            return Err(StepError::NoConvergence {
                stage: Stage::Contacts,
                iterations: round,
                residual: deepest_overlap(x, radius, cell, wall.is_some()).to_f64(),
            });
        }
    }
}

/// A dependent set that the solve found contradictory ([`StepError::Infeasible`]) is
/// a claim about the linearisation at its iterate. Where every row already holds at
/// the start of the step, the start is a point that meets them all: the geometry is
/// feasible, and the step is too long for the linearisation (its rows turned too far):
/// [`StepError::Degenerate`] on the dependent set's first row, which a shorter step
/// can avoid. Other errors pass unchanged.
fn too_long<T: Real>(
    e: StepError,
    rows: &[Bond<T>],
    one_sided: usize,
    start: &[T::V3],
    wall: Option<T>,
    p: &Params<T>,
) -> StepError {
    let StepError::Infeasible { constraints, .. } = e else {
        return e;
    };
    // The last step left its rows within the tolerance and its other pairs overlapping
    // by at most that (measured as the solve measures them, which a sweep stops just
    // inside): four tolerances here, far below any contradiction a start can hold.
    let tol = p.solver.tolerance * T::from_f64(4.0);
    let cell = super::cell(p);
    let holds = rows.iter().enumerate().all(|(k, b)| {
        // A pin row is measured from the start: it holds there.
        if b.is_pin() {
            return true;
        }
        let (gap, d) = match b.is_wall() {
            true => {
                let h = wall.unwrap_or(T::ZERO);
                (T::xyz(start[b.i])[2] - h - b.length, b.length)
            }
            false => (
                T::norm(b.separation(start, cell.as_ref())) - b.length,
                b.length,
            ),
        };
        let err = gap / d;
        match k >= one_sided {
            true => err >= -tol,
            false => err.abs() <= tol,
        }
    });
    match holds {
        true => StepError::Degenerate {
            bond: constraints[0],
            row: Row::of(rows, constraints[0], one_sided),
        },
        false => e,
    }
}

/// `z += sign * height` for every position (into the wall's frame with `sign = -1`,
/// back with `+1`); nothing without a wall.
fn shift<T: Real>(x: &mut [T::V3], wall: Option<T>, sign: T) {
    if let Some(h) = wall {
        let dz = T::v3(T::ZERO, T::ZERO, h * sign);
        for xi in x.iter_mut() {
            *xi += dz;
        }
    }
}

/// Appends a wall link for every sphere whose centre is closer than `reach` times its
/// radius to the plane `z = height` (or below it) and has none yet; returns how many
/// were added.
fn add_wall<T: Real>(
    pos: &[T::V3],
    height: T,
    radius: &[T],
    reach: T,
    set: &mut Active<'_, T>,
) -> Result<usize, StepError> {
    let mut added = 0;
    for (i, (&r, &a)) in pos.iter().zip(radius).enumerate() {
        if !(T::xyz(r)[2] - height < a * reach) {
            continue;
        }
        if set.held().iter().any(|l| l.is_wall() && l.i == i) {
            continue;
        }
        set.push(Bond::wall(i, a))?;
        added += 1;
    }
    Ok(added)
}

/// The one-sided constraints of a step in the link storage: `nc` active ones after
/// the `nb` bonds, and at the pool's far end the `released` ones (latest last from the
/// end) that the anti-cycling rule remembers.
struct Active<'s, T: Real> {
    nb: usize,
    pool: usize,
    links: &'s mut [Bond<T>],
    nc: &'s mut usize,
    released: &'s mut usize,
}

impl<'s, T: Real> Active<'s, T> {
    fn new(
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
    fn release_pulling(&mut self, lambda: &[T]) -> Option<usize> {
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
fn add_pairs<T: Real>(
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

/// Largest relative overlap `1 - |r_ij| / (a_i + a_j)` (the minimum image in a box), and
/// with a wall `1 - z_i / a_i` (positions in the wall's frame), for the error report.
fn deepest_overlap<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    cell: Option<Periodic<T>>,
    wall: bool,
) -> T {
    let mut worst = T::ZERO;
    for i in 0..pos.len() {
        if wall {
            worst = worst.max(T::ONE - T::xyz(pos[i])[2] / radius[i]);
        }
        for j in 0..i {
            let sigma = radius[i] + radius[j];
            worst = worst.max(T::ONE - T::norm(image(cell.as_ref(), pos[i] - pos[j])) / sigma);
        }
    }
    worst
}
