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
//!
//! **The ceiling** of a slit ([`Params::slit`]) holds the spheres below it the same
//! way: a sphere whose centre would end above `ceiling - a_i` gets a ceiling link
//! ([`Bond::ceiling`]: the wall link with the normal `-z`, measured from the ceiling's
//! height in the floor's frame), so a buoyant sphere comes to rest on it, pushed along
//! `-z`. The pool holds one such link per sphere per surface.
//!
//! This file holds the projection's entry ([`project_overdamped`]) and who solves a
//! round ([`Along`], [`Round`]); `rounds.rs` the active-set loop ([`project_along`]) and
//! its error reports; `search.rs` the search for pairs and wall links to add and the
//! pool of one-sided constraints ([`search::Active`]: push, release, anti-cycling).

mod rounds;
mod search;

/// The height of the ceiling the ceiling links hold ([`Bond::ceiling`]) in the frame the
/// projection runs in (the floor's: the ceiling's height less the floor's); zero
/// without a ceiling, or without the `contacts` feature (no link then).
#[cfg(feature = "slit")]
pub(in crate::integrate) fn ceiling<T: Real>(p: &Params<T>) -> T {
    let s = p.place().surfaces();
    match (s.ceiling(), cfg!(feature = "contacts")) {
        (Some(c), true) => c - s.floor().unwrap_or(T::ZERO),
        _ => T::ZERO,
    }
}

pub(super) use rounds::project_along;

use super::{Sums, mobility_metric, project_positions};
use crate::bonds::Bond;
use crate::constraints::{Scratch, SolveStats};
use crate::error::StepError;
use crate::linalg::Mob;
use crate::params::Params;
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
