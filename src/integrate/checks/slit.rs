//! The slit's part of a step's checks ([`check_slit`]): its walls, the kernel's
//! features, the method that holds both walls, and no sphere past either at the start
//! (in a candidate, the acceptance asks every hard surface of the place, `Surface`).

use crate::error::{ParticleError, StepError};
use crate::geometry::Place;
use crate::params::{Method, Params};
use crate::particles::State;
use crate::real::Real;

/// What a slit's parameters must be wherever its mobility is evaluated (a step, or a
/// front end's mobility): finite walls, the ceiling above the floor, nothing named
/// beside it, and the kernel built with its `slit` feature.
pub(in crate::integrate) fn check_slit_place<T: Real>(p: &Params<T>) -> Result<(), StepError> {
    let Place::Slit(b) = p.place() else {
        return Ok(());
    };
    if !(b.floor.is_finite() && b.ceiling.is_finite() && b.ceiling > b.floor) {
        return Err(StepError::BadParameter(
            "slit (finite floor and ceiling, the ceiling above the floor)",
        ));
    }
    if b.clash {
        return Err(StepError::Unsupported(
            "a slit with a wall or a periodic box beside it",
        ));
    }
    if !cfg!(feature = "slit") {
        return Err(StepError::Unsupported(
            "a slit: the kernel was built without its `slit` feature",
        ));
    }
    Ok(())
}

/// Checks a step in a slit: its parameters ([`check_slit_place`]); the kernel's
/// `contacts` feature (each wall is held as a one-sided constraint); a method whose
/// position projection holds the walls (Overdamped, Overdamped2); no near field (its
/// sphere-wall corrections are the one wall's); and no sphere past either wall's
/// contact height at the start (beyond the contacts' tolerance).
pub(super) fn check_slit<T: Real>(p: &Params<T>, state: &State<'_, T>) -> Result<(), StepError> {
    if p.place().surfaces().len() < 2 {
        return Ok(());
    }
    check_slit_place(p)?;
    if !cfg!(feature = "contacts") {
        return Err(StepError::Unsupported(
            "a slit: the kernel was built without its `contacts` feature",
        ));
    }
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return Err(StepError::Unsupported(
            "a slit with a method other than Overdamped or Overdamped2",
        ));
    }
    if p.near_on() {
        return Err(StepError::Unsupported(
            "the near field (Params::near) in a slit",
        ));
    }
    for s in p.place().surfaces().iter() {
        if let Some(particle) = s.first_crossed(state.pos, state.radius, p.solver.tolerance) {
            return Err(ParticleError::BelowWall { particle }.into());
        }
    }
    Ok(())
}
