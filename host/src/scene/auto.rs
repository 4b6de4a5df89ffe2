//! `[model] level = "auto"`: the cheapest model whose estimated error stays under a
//! stated tolerance, from the scene's dimensionless numbers.
//!
//! Tolerance: RMS position error of 0.1 (smallest) radius over 5 time units. Rules and
//! their measured justification (`host-demo chart`, `models.csv`, 1+24 bead helix):
//!
//! * **Inertia.** Overdamped against inertial RPY at Stokes number `St` errs by about
//!   `20 St` radii at t = 5 (measured 0.199 at St = 0.01, 2.00 at St = 0.1). So
//!   overdamped when `20 St <= 0.1`, i.e. `St <= 0.005`; otherwise the stable-drag
//!   inertial method (the paper's explicit drag is never chosen: it needs
//!   `dt < 2 m / zeta`).
//! * **Hydrodynamic interactions.** The pair mobility relative to the self mobility is
//!   `3 a_i / (4 r_ij)` to leading order; `I = max_i sum_j 3 a_i / (4 r_ij)` measures how
//!   much the others move a sphere. Free-draining errs by 15-17 radii on the helix
//!   (I = 4.5); free-draining is chosen only when `I <= 0.01`. Oseen is never chosen:
//!   it costs the same as RPY (4.7e-3 vs 4.9e-3 s per time unit), errs more (0.34 vs
//!   0.20 at St = 0.01) and is not positive definite at close range.
//! * **Rotation.** Resolving rotation changes positions by 1e-4 (St = 0.01) to 4e-3
//!   (St = 1): below the tolerance, so it is resolved only for an inertial scene in a
//!   rotating fluid, where the spheres' spin-up is itself of interest.

use serde::Serialize;

use crate::scene::{Hydrodynamics, Method, Scene};

/// Stated tolerance: RMS position error in radii over 5 time units.
pub const TOLERANCE: f64 = 0.1;
/// Measured error of dropping inertia, per unit Stokes number (radii at t = 5).
pub const INERTIA_ERROR_PER_ST: f64 = 20.0;
/// Interaction strength below which free-draining is accurate enough.
pub const FREE_DRAINING_MAX: f64 = 0.01;

/// What `auto` chose and why (written to `summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Choice {
    /// Hydrodynamic model.
    #[serde(serialize_with = "super::names::serialize")]
    pub hydrodynamics: Hydrodynamics,
    /// Whether inertia is resolved.
    pub inertia: bool,
    /// Whether rotation is resolved.
    pub rotation: bool,
    /// Integrator.
    #[serde(serialize_with = "super::names::serialize")]
    pub method: Method,
    /// Largest particle Stokes number `m U / (6 pi eta a^2)`.
    pub stokes_number: f64,
    /// Interaction strength `max_i sum_j 3 a_i / (4 r_ij)`.
    pub interaction: f64,
    /// The rule that decided, in words.
    pub reason: String,
}

/// Largest particle Stokes number, with `U` the lone-sphere settling speed plus the
/// uniform flow speed.
pub fn stokes_number(scene: &Scene) -> f64 {
    let eta = scene.fluid.viscosity;
    let g = scene.gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
    let flow = scene
        .flow
        .velocity
        .iter()
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt();
    scene
        .particles
        .iter()
        .map(|p| {
            let a = p.radius;
            let vol = 4.0 / 3.0 * std::f64::consts::PI * a.powi(3);
            let weight = ((p.density - scene.fluid.density) * vol * g).abs();
            let zeta = 6.0 * std::f64::consts::PI * eta * a;
            let u = weight / zeta + flow;
            p.density * vol * u / (zeta * a)
        })
        .fold(0.0, f64::max)
}

/// `max_i sum_j 3 a_i / (4 r_ij)`.
pub fn interaction(scene: &Scene) -> f64 {
    let ps = &scene.particles;
    (0..ps.len())
        .map(|i| {
            (0..ps.len())
                .filter(|&j| j != i)
                .map(|j| {
                    let r = (0..3)
                        .map(|k| (ps[i].position[k] - ps[j].position[k]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    0.75 * ps[i].radius / r
                })
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// The (method, rotation) pairs the rules can pick, without and with inertia, for an
/// ambient vorticity: what an auto-level scene is sized for before it is resolved.
pub fn possible_methods(vorticity: [f64; 3]) -> [(Method, bool); 2] {
    let spinning = vorticity.iter().any(|&w| w != 0.0);
    [
        (Method::Overdamped, false),
        (Method::RattleStable, spinning),
    ]
}

/// Applies the rules to `scene`.
pub fn choose(scene: &Scene) -> Choice {
    let st = stokes_number(scene);
    let inter = interaction(scene);
    let inertia = INERTIA_ERROR_PER_ST * st > TOLERANCE;
    let hydro = if inter <= FREE_DRAINING_MAX {
        Hydrodynamics::FreeDraining
    } else {
        Hydrodynamics::Rpy
    };
    let (method, rotation) = possible_methods(scene.flow.vorticity)[usize::from(inertia)];
    let reason = format!(
        "St = {st:.3e}: dropping inertia errs ~{:.2e} radii (tolerance {TOLERANCE}) -> {}; \
         interaction {inter:.3} {} {FREE_DRAINING_MAX} -> {}; rotation {}",
        INERTIA_ERROR_PER_ST * st,
        if inertia {
            "inertial (stable drag)"
        } else {
            "overdamped"
        },
        if inter <= FREE_DRAINING_MAX {
            "<="
        } else {
            ">"
        },
        if inter <= FREE_DRAINING_MAX {
            "free-draining"
        } else {
            "RPY"
        },
        if rotation {
            "resolved (inertial, rotating fluid)"
        } else {
            "not resolved"
        },
    );
    Choice {
        hydrodynamics: hydro,
        inertia,
        rotation,
        method,
        stokes_number: st,
        interaction: inter,
        reason,
    }
}

/// `scene` with the choice applied.
pub fn apply(scene: &Scene, c: &Choice) -> Scene {
    let mut s = scene.clone();
    s.model.hydrodynamics = c.hydrodynamics;
    s.model.inertia = c.inertia;
    s.model.rotation = c.rotation;
    s.integrator.method = c.method;
    s
}
