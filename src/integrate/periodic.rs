//! The mobility of a step in a periodic box (feature `periodic`): the Ewald sums of
//! `mobility::periodic` with parameters derived once per step.
//!
//! `xi` and the cutoffs come from the box and the step's largest radius by
//! [`Ewald::new`], once, in the step's checks (`check_periodic`), and every product,
//! assembly and matrix-free metric block of the step reads that one copy
//! ([`super::stages::Sums`]): they depend on the box and the radii only, which a step
//! does not change. Not held in the parameters: the largest radius is the state's (a
//! radius above a stored one would be refused) and `Params` stays small and `Copy`.
//! The assembly is serial (the banded assembly of [`crate::parallel`] is free space's);
//! the products over the assembled matrix still run in bands.

use crate::cell::Periodic;
use crate::error::StepError;
use crate::mobility::periodic::{self, Ewald};
use crate::params::Params;
use crate::real::Real;

/// The Ewald parameters for this box and these spheres (every radius at most the
/// largest, so the sums accept each one).
pub(super) fn ewald<T: Real>(cell: Periodic<T>, radius: &[T]) -> Result<Ewald<T>, StepError> {
    let a_max = radius.iter().fold(T::ZERO, |m, &a| m.max(a));
    Ok(Ewald::new(cell, a_max)?)
}

/// `mu_tt` of the box into the packed lower triangle `mu` ([`periodic::assemble_tt`]).
pub(super) fn assemble<T: Real>(
    p: &Params<T>,
    ew: &Ewald<T>,
    pos: &[T::V3],
    radius: &[T],
    mu: &mut [T::M3],
) -> Result<(), StepError> {
    Ok(periodic::assemble_tt(ew, p.viscosity, pos, radius, mu)?)
}

/// `u = mu_tt f` in the box without storing `mu_tt` ([`periodic::tt_product`]).
pub(super) fn product<T: Real>(
    p: &Params<T>,
    ew: &Ewald<T>,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    u: &mut [T::V3],
) -> Result<(), StepError> {
    Ok(periodic::tt_product(ew, p.viscosity, pos, radius, f, u)?)
}
