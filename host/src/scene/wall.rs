//! A no-slip plane wall below the spheres: the `[wall]` table.
//!
//! ```toml
//! [wall]
//! height = -30.0   # the plane z = height; every sphere starts on or above it
//! ```
//!
//! The plane's normal is `+z` (gravity should point at it). It is the kernel's
//! `Params::wall`: a one-sided constraint in the position solve (a sphere that would
//! cross it is held at contact, in the same solve as the bonds and the hard contacts)
//! and, where the kernel has it, the wall's correction of the mobility. Overdamped
//! methods only (`level = "manual"`); thermal noise only with `"overdamped"`.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::raw::{Bound, S};
use super::resolve::BodySpans;
use super::{Integrator, Level, Method, Model, Particle};

/// The plane `z = height` below the spheres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Wall {
    /// The plane's `z`.
    pub height: f64,
}

impl Wall {
    /// Gap between sphere `p` and the wall: `z - height - radius` (negative: it
    /// crosses the wall).
    pub fn gap(&self, position: [f64; 3], radius: f64) -> f64 {
        position[2] - self.height - radius
    }
}

/// `[wall]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawWall {
    height: S<f64>,
}

/// Resolves `[wall]` (its span places a missing height).
pub(super) fn resolve(raw: &Spanned<RawWall>) -> Result<Wall, Issue> {
    if raw.get_ref().height.is_none() {
        return Err(issue(
            raw.span(),
            "missing field `height` in [wall] (the plane z = height)",
        ));
    }
    let height = super::raw::number(&raw.get_ref().height, 0.0, "wall height", Bound::Any)?;
    Ok(Wall { height })
}

/// The wall runs where the kernel holds it: the overdamped methods, chosen by hand.
pub(super) fn check_method(
    raw: &Spanned<RawWall>,
    model: &Model,
    integrator: &Integrator,
) -> Result<(), Issue> {
    let at = raw
        .get_ref()
        .height
        .as_ref()
        .map_or(raw.span(), |h| h.span());
    overdamped_only(at, "wall", model, integrator)
}

/// The overdamped methods, chosen by hand, hold a wall (`what`: "wall" or "slit");
/// refused at `at` otherwise.
pub(super) fn overdamped_only(
    at: std::ops::Range<usize>,
    what: &str,
    model: &Model,
    integrator: &Integrator,
) -> Result<(), Issue> {
    if model.level == Level::Auto {
        return Err(issue(
            at,
            format!(
                "a {what} needs level = \"manual\" (the automatic level may pick an inertial method, which has no {what})"
            ),
        ));
    }
    if !matches!(integrator.method, Method::Overdamped | Method::Overdamped2) {
        return Err(issue(
            at,
            format!(
                "a {what} needs method \"overdamped\" or \"overdamped2\" (the scene's is {:?})",
                integrator.method
            ),
        ));
    }
    Ok(())
}

/// Refuses a sphere that starts below the wall or crossing it, at its position.
pub(super) fn check_particles(
    wall: Wall,
    particles: &[Particle],
    spans: &BodySpans,
) -> Result<(), Issue> {
    match below(wall, particles) {
        None => Ok(()),
        Some((k, message)) => Err(issue(spans.position(k), message)),
    }
}

/// The first sphere below the wall or crossing it (to the rounding of the numbers
/// written: a gap of `-1e-12` radii, or of 4 epsilons of `|z| + |height| + a` far from
/// the origin, as the kernel allows, is touching), and what is wrong with it.
pub(super) fn below(wall: Wall, particles: &[Particle]) -> Option<(usize, String)> {
    let k = particles.iter().position(|p| {
        let (z, a) = (p.position[2], p.radius);
        let rounding = 4.0 * f64::EPSILON * (z.abs() + wall.height.abs() + a);
        wall.gap(p.position, a) < -(1e-12 * a + rounding)
    })?;
    let p = &particles[k];
    Some((
        k,
        format!(
            "particle {k} is below the wall or crosses it at t = 0 (centre z = {}, radius {}, wall height {}: the centre must be at least {} high)",
            p.position[2],
            p.radius,
            wall.height,
            wall.height + p.radius
        ),
    ))
}

impl super::Scene {
    /// This scene above a wall at `height` (as a `[wall]` table would put it): the
    /// height must be finite, the method overdamped and every sphere on or above it.
    pub fn with_wall(mut self, height: f64) -> Result<super::Scene, String> {
        if !height.is_finite() {
            return Err(format!("the wall height must be finite, not {height}"));
        }
        if !matches!(
            self.integrator.method,
            Method::Overdamped | Method::Overdamped2
        ) {
            return Err(format!(
                "a wall needs method \"overdamped\" or \"overdamped2\" (the scene's is {:?})",
                self.integrator.method
            ));
        }
        let wall = Wall { height };
        if let Some((_, message)) = below(wall, &self.particles) {
            return Err(message);
        }
        self.wall = Some(wall);
        Ok(self)
    }
}
