//! The wall's part of a step's checks: its height, the kernel's features and the
//! method that holds it, and no sphere below it at the start ([`check_wall`]; in a
//! candidate, the acceptance asks every hard surface of the place, `Surface`).

use crate::error::{ParticleError, StepError};
use crate::geometry::Surface;
use crate::params::{Method, Params};
use crate::particles::State;
use crate::real::Real;

/// Checks the wall: a finite height; the kernel built with its `wall` feature (the
/// wall's mobility, `mobility::wall`) and its `contacts` feature (the wall is held as
/// a one-sided constraint); a method whose position projection holds it (Overdamped,
/// Overdamped2); and no sphere below its contact height `height + a_i` (beyond the
/// contacts' tolerance: the last step's wall contacts end within it).
pub(super) fn check_wall<T: Real>(p: &Params<T>, state: &State<'_, T>) -> Result<(), StepError> {
    let Some(height) = p.place().wall() else {
        return Ok(());
    };
    if !height.is_finite() {
        return Err(StepError::BadParameter("wall.height (finite)"));
    }
    if !cfg!(feature = "wall") {
        return Err(StepError::Unsupported(
            "a wall: the kernel was built without its `wall` feature",
        ));
    }
    if !cfg!(feature = "contacts") {
        return Err(StepError::Unsupported(
            "a wall: the kernel was built without its `contacts` feature",
        ));
    }
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return Err(StepError::Unsupported(
            "a wall with a method other than Overdamped or Overdamped2",
        ));
    }
    match Surface::floor(height).first_crossed(state.pos, state.radius, p.solver.tolerance) {
        Some(particle) => Err(ParticleError::BelowWall { particle }.into()),
        None => Ok(()),
    }
}
