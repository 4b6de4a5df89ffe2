//! The mobility of a step in a periodic box (feature `periodic`): the Ewald sums of
//! `mobility::periodic` with parameters derived once per step.
//!
//! `xi` and the cutoffs come from the box and the step's largest radius by
//! [`Ewald::new`], once, in the step's checks (`check_periodic`), and every product,
//! assembly and matrix-free metric block of the step reads that one copy
//! ([`super::stages::Sums`]): they depend on the box and the radii only, which a step
//! does not change. Not held in the parameters: the largest radius is the state's (a
//! radius above a stored one would be refused) and `Params` stays small and `Copy`.
//! The assembly and the products run in the bands of [`crate::parallel`] (each block
//! summed on its own, so the same bits on any number of threads); so does the
//! matrix-free product's real-space half ([`periodic::free_product`]).

use crate::cell::Periodic;
use crate::error::StepError;
use crate::mobility::periodic::{self, Ewald};
#[cfg(feature = "pse")]
use crate::mobility::pse::{Pse, PseSize, PseStorage};
use crate::mobility::sums::BoxSums;
#[cfg(feature = "pse")]
use crate::mobility::sums::PseStep;
use crate::params::Params;
use crate::real::Real;

/// What a step in a box holds for its products ([`super::stages::Sums`] borrows it):
/// the Ewald parameters, or PSE's ([`Params::pse`]).
#[derive(Debug)]
pub(super) enum Held<T: Real> {
    /// The exact Ewald sums.
    Ewald(Ewald<T>),
    /// The PSE fast path.
    #[cfg(feature = "pse")]
    Pse(Pse<T>),
}

/// The largest radius of the step (the sums accept every radius up to it).
fn a_max<T: Real>(radius: &[T]) -> T {
    radius.iter().fold(T::ZERO, |m, &a| m.max(a))
}

/// The PSE parameters of this box, these spheres and the tolerance `tol`.
#[cfg(feature = "pse")]
pub(super) fn pse<T: Real>(cell: Periodic<T>, radius: &[T], tol: f64) -> Result<Pse<T>, StepError> {
    Ok(Pse::new(cell, a_max(radius), tol)?)
}

/// The PSE storage a step of these spheres needs with `p`
/// ([`Workspace::with_pse`](crate::Workspace::with_pse)): `Some` where the step sums
/// its box by PSE ([`Params::pse`], a box whose images interact), from the same
/// parameters the step derives; `None` where it needs none. A host sizes its arrays
/// with it before the first step (the radii do not change during a run).
#[cfg(feature = "pse")]
pub fn pse_storage<T: Real>(p: &Params<T>, radius: &[T]) -> Result<Option<PseSize>, StepError> {
    match (super::stages::ewald_cell(p), p.pse) {
        (Some(c), Some(tol)) => Ok(Some(pse(c, radius, tol)?.storage(radius.len()))),
        _ => Ok(None),
    }
}

/// The Ewald parameters for this box and these spheres (every radius at most the
/// largest, so the sums accept each one).
pub(super) fn ewald<T: Real>(cell: Periodic<T>, radius: &[T]) -> Result<Ewald<T>, StepError> {
    Ok(Ewald::new(cell, a_max(radius))?)
}

/// `mu_tt` of the box into the packed lower triangle `mu`, in bands through `par`
/// ([`periodic::assemble`]: the blocks of [`periodic::assemble_tt`]).
pub(super) fn assemble<T: Real>(
    p: &Params<T>,
    ew: &Ewald<T>,
    pos: &[T::V3],
    radius: &[T],
    mu: &mut [impl crate::linalg::Block<T>],
    par: &dyn crate::parallel::Parallel,
) -> Result<(), StepError> {
    Ok(periodic::assemble(par, ew, p.viscosity, pos, radius, mu)?)
}

/// The caller's PSE arrays as the step's storage, after checking them against the
/// step's PSE parameters (`None` where the step sums by Ewald or has no box).
#[cfg(feature = "pse")]
pub(super) fn pse_store<'a, T: Real>(
    held: Option<&'a Held<T>>,
    n: usize,
    (complex, index, vectors): crate::workspace::PseSlices<'a, T>,
    par: &'a dyn crate::parallel::Parallel,
) -> Result<Option<PseStep<'a, T>>, StepError> {
    let Some(Held::Pse(pse)) = held else {
        return Ok(None);
    };
    let need = pse.storage(n);
    if complex.len() < need.complex || index.len() < need.index || vectors.len() < need.vectors {
        return Err(crate::mobility::pse::PseError::Storage {
            need: [need.complex, need.index, need.vectors],
            have: [complex.len(), index.len(), vectors.len()],
        }
        .into());
    }
    let store = PseStorage::new(complex, index, vectors).with_parallel(par);
    Ok(Some(PseStep::new(pse, store)))
}

/// The step's sums ([`super::stages::Sums`]) over what its checks hold and, for PSE,
/// the storage [`pse_store`] made.
#[cfg(feature = "pse")]
pub(super) fn sums<'a, T: Real>(
    held: Option<&'a Held<T>>,
    store: Option<&'a PseStep<'_, T>>,
) -> super::stages::Sums<'a, T> {
    match (held?, store) {
        (Held::Ewald(e), _) => Some(BoxSums::Ewald(e)),
        (Held::Pse(_), Some(s)) => Some(BoxSums::Pse(s)),
        // `pse_store` makes the storage for every PSE step.
        (Held::Pse(_), None) => None,
    }
}

/// The step's sums ([`super::stages::Sums`]): Ewald's (no `pse` feature).
#[cfg(not(feature = "pse"))]
pub(super) fn sums<T: Real>(held: Option<&Held<T>>) -> super::stages::Sums<'_, T> {
    match held? {
        Held::Ewald(e) => Some(BoxSums::Ewald(e)),
    }
}
