//! The raw (spanned) form of a scene file, as deserialized: every value that is checked
//! later keeps its byte span, and every table refuses unknown keys.

use serde::Deserialize;
use toml::Spanned;

use super::error::{Issue, issue};
use super::names::Name;
use super::{HeadEnd, Hydrodynamics, Level, Method, Overlap, Precision, Solver};

pub(super) type S<T> = Option<Spanned<T>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub(super) fluid: Option<RawFluid>,
    pub(super) gravity: Option<RawGravity>,
    pub(super) flow: Option<RawFlow>,
    #[serde(rename = "particle")]
    pub(super) particles: S<Vec<RawParticle>>,
    #[serde(rename = "bond")]
    pub(super) bonds: S<Vec<RawBond>>,
    pub(super) helix: S<RawHelix>,
    pub(super) model: Option<RawModel>,
    pub(super) integrator: S<RawIntegrator>,
    pub(super) output: Option<RawOutput>,
    pub(super) contact: S<super::contact::RawContact>,
    pub(super) brownian: Option<super::thermal::RawBrownian>,
    pub(super) wall: S<super::wall::RawWall>,
    pub(super) slit: S<super::slit::RawSlit>,
    #[serde(rename = "box")]
    pub(super) periodic: S<super::periodic::RawBox>,
    pub(super) suspension: S<super::suspension::RawSuspension>,
    pub(super) cloud: S<super::cloud::RawCloud>,
    pub(super) free_space: S<super::free_space::RawFreeSpace>,
    pub(super) floor: S<super::floor::RawFloor>,
    pub(super) near_field: S<super::near::RawNearField>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFluid {
    pub(super) viscosity: S<f64>,
    pub(super) density: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGravity {
    pub(super) acceleration: S<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFlow {
    pub(super) velocity: S<[f64; 3]>,
    pub(super) vorticity: S<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawParticle {
    pub(super) position: Spanned<[f64; 3]>,
    pub(super) radius: Spanned<f64>,
    pub(super) density: S<f64>,
    pub(super) velocity: S<[f64; 3]>,
    pub(super) angular_velocity: S<[f64; 3]>,
    pub(super) species: S<String>,
    pub(super) fixed: S<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBond {
    pub(super) between: Spanned<[usize; 2]>,
    pub(super) length: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHelix {
    pub(super) tails: S<usize>,
    pub(super) head_ratio: S<f64>,
    pub(super) dhat: S<f64>,
    pub(super) head_end: Option<HeadEnd>,
    pub(super) radius: S<f64>,
    pub(super) pitch: S<f64>,
    pub(super) density: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawModel {
    pub(super) hydrodynamics: Option<Name<Hydrodynamics>>,
    pub(super) inertia: Option<bool>,
    pub(super) rotation: Option<bool>,
    pub(super) level: Option<Level>,
    pub(super) overlap: Option<Overlap>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawIntegrator {
    pub(super) method: Name<Method>,
    pub(super) dt: Spanned<f64>,
    pub(super) duration: Spanned<f64>,
    pub(super) solver: Option<Name<Solver>>,
    pub(super) tolerance: S<f64>,
    pub(super) max_iterations: S<usize>,
    pub(super) precision: Option<Precision>,
    pub(super) stiffness: S<f64>,
    pub(super) fene: S<f64>,
    pub(super) matrix_free: Option<Spanned<bool>>,
    pub(super) compact_products: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawOutput {
    pub(super) every: S<usize>,
}

/// Which bound a number must respect.
#[derive(Clone, Copy)]
pub(super) enum Bound {
    Positive,
    NonNegative,
    /// Finite, any sign.
    Any,
}

/// Takes a spanned number (or its default), checks finiteness and bound.
pub(super) fn number(value: &S<f64>, default: f64, name: &str, bound: Bound) -> Result<f64, Issue> {
    let Some(v) = value else {
        return Ok(default);
    };
    let x = *v.get_ref();
    let bad = match bound {
        _ if !x.is_finite() => Some("a finite number"),
        Bound::Positive if x <= 0.0 => Some("> 0"),
        Bound::NonNegative if x < 0.0 => Some(">= 0"),
        _ => None,
    };
    match bad {
        Some(what) => Err(issue(
            v.span(),
            format!(
                "{name} must be {what}, not {}",
                crate::output::format_f64(x)
            ),
        )),
        None => Ok(x),
    }
}

pub(super) fn vector(
    value: &S<[f64; 3]>,
    default: [f64; 3],
    name: &str,
) -> Result<[f64; 3], Issue> {
    match value {
        None => Ok(default),
        Some(v) => finite_vector(v, name),
    }
}

pub(super) fn finite_vector(v: &Spanned<[f64; 3]>, name: &str) -> Result<[f64; 3], Issue> {
    let x = *v.get_ref();
    if x.iter().all(|c| c.is_finite()) {
        Ok(x)
    } else {
        Err(issue(
            v.span(),
            format!("{name} must have finite components, not {x:?}"),
        ))
    }
}

pub(super) fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}
