//! A slit between two no-slip plane walls: the `[slit]` table.
//!
//! ```toml
//! [slit]
//! floor = 0.0      # the plane z = floor below every sphere
//! ceiling = 20.0   # the plane z = ceiling above every sphere (above the floor)
//! ```
//!
//! It is the kernel's `Params::slit` (`docs/GEOMETRY.md`, "The slit"): the mobility is
//! the linear superposition of both walls' images, which serves single spheres and a
//! few spheres within about a slit width of each other (the kernel refuses a sphere
//! whose mobility across the walls is not positive). The floor holds spheres as
//! `[wall]` does; the ceiling has no contact links: a step that would carry a sphere
//! past it is refused. Overdamped methods only (`level = "manual"`); no `[wall]`,
//! `[box]` or `[near_field]` beside it.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::raw::{Bound, S};
use super::resolve::BodySpans;
use super::{Integrator, Model, Particle, Wall};

/// The planes `z = floor` below the spheres and `z = ceiling` above them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Slit {
    /// The floor's `z`.
    pub floor: f64,
    /// The ceiling's `z` (above the floor).
    pub ceiling: f64,
}

/// `[slit]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSlit {
    floor: S<f64>,
    ceiling: S<f64>,
}

/// Resolves `[slit]`: both planes given and finite, the ceiling above the floor.
pub(super) fn resolve(raw: &Spanned<RawSlit>) -> Result<Slit, Issue> {
    let r = raw.get_ref();
    for (v, key) in [(&r.floor, "floor"), (&r.ceiling, "ceiling")] {
        if v.is_none() {
            return Err(issue(
                raw.span(),
                format!("missing field `{key}` in [slit] (the plane z = {key})"),
            ));
        }
    }
    let floor = super::raw::number(&r.floor, 0.0, "slit floor", Bound::Any)?;
    let ceiling = super::raw::number(&r.ceiling, 0.0, "slit ceiling", Bound::Any)?;
    if ceiling <= floor {
        let at = r.ceiling.as_ref().map_or(raw.span(), |c| c.span());
        return Err(issue(
            at,
            format!("the slit ceiling ({ceiling}) must be above its floor ({floor})"),
        ));
    }
    Ok(Slit { floor, ceiling })
}

/// The slit runs where the kernel holds it: the overdamped methods, chosen by hand,
/// and no other geometry beside it.
pub(super) fn check(
    raw: &Spanned<RawSlit>,
    model: &Model,
    integrator: &Integrator,
    others: [(bool, &str); 2],
) -> Result<(), Issue> {
    let at = raw.span();
    if let Some((_, name)) = others.iter().find(|(named, _)| *named) {
        return Err(issue(
            at,
            format!(
                "a [slit] with a {name} is not supported (the slit is the only geometry of its scene)"
            ),
        ));
    }
    super::wall::overdamped_only(at, "slit", model, integrator)
}

/// Refuses a sphere that starts below the floor or above the ceiling, or crossing
/// either, at its position (to the rounding the wall allows, `wall::below`).
pub(super) fn check_particles(
    slit: Slit,
    particles: &[Particle],
    spans: &BodySpans,
) -> Result<(), Issue> {
    let floor = Wall { height: slit.floor };
    if let Some((k, message)) = super::wall::below(floor, particles) {
        return Err(issue(
            spans.position(k),
            message.replace("wall", "slit floor"),
        ));
    }
    // The ceiling is the floor in the mirror z -> -z.
    let mirrored: Vec<Particle> = particles
        .iter()
        .map(|p| {
            let mut m = *p;
            m.position[2] = -p.position[2];
            m
        })
        .collect();
    let ceiling = Wall {
        height: -slit.ceiling,
    };
    if let Some((k, _)) = super::wall::below(ceiling, &mirrored) {
        let p = &particles[k];
        return Err(issue(
            spans.position(k),
            format!(
                "particle {k} is above the slit ceiling or crosses it at t = 0 (centre z = {}, radius {}, ceiling {}: the centre must be at most {} high)",
                p.position[2],
                p.radius,
                slit.ceiling,
                slit.ceiling - p.radius
            ),
        ));
    }
    Ok(())
}
