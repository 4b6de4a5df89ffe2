//! The budgets a scene is sized against from its counts alone, before anything is
//! generated: its step storage for each method it may run (the kernel's layout,
//! [`crate::sizing`]) and its trajectory files. Apart because the body
//! (`body.rs`) asks them for each kind of body, and they place the error at the value
//! that set the count.

use crate::scene::error::{Issue, too_large};
use crate::scene::raw::{RawBond, RawParticle};
use crate::scene::{Contact, Flow, Integrator, Level, Model, Thermal};
use crate::sizing::{Plan, TooLarge};

/// Refuses a run whose trajectory files would exceed `limit` bytes (estimated from the
/// frame count and the particle count, before anything is generated).
pub(super) fn check_output(
    integrator: &Integrator,
    every: usize,
    n: usize,
    limit: u64,
) -> Result<(), String> {
    let frames = (integrator.steps() / every.max(1)) as f64 + 2.0;
    let bytes = frames * crate::sizing::frame_bytes(n);
    if bytes > limit as f64 {
        return Err(format!(
            "{frames:.0} frames of {n} particles make about {} of trajectory files, over the limit of {}; raise [output] every, shorten the duration or use `run --max-output`",
            crate::sizing::human(bytes.min(u64::MAX as f64) as u64),
            crate::sizing::human(limit)
        ));
    }
    Ok(())
}

/// What sizes the scene's storage: its own method, or with `level = "auto"` each method
/// the rules may pick; in a box summed by PSE (`pse`) without the stored mobility.
pub(super) fn plans(
    model: &Model,
    integrator: &Integrator,
    flow: &Flow,
    contact: Option<Contact>,
    brownian: Option<Thermal>,
    ((wall, slit), pse, near, fast): ((bool, bool), bool, bool, bool),
) -> Vec<Plan> {
    let plan = |(method, rotation)| Plan {
        method,
        rotation,
        solver: integrator.solver,
        precision: integrator.precision,
        contact,
        brownian,
        wall,
        slit,
        matrix_free: integrator.matrix_free,
        compact_products: integrator.compact_products,
        pse,
        near,
        fast,
    };
    match model.level {
        Level::Manual => vec![plan((integrator.method, model.rotation))],
        Level::Auto => crate::auto::possible_methods(flow.vorticity)
            .map(plan)
            .to_vec(),
    }
}

pub(super) fn fits(plans: &[Plan], n: usize, b: usize, limit: usize) -> Result<(), TooLarge> {
    plans
        .iter()
        .try_for_each(|p| p.check(n, b, limit).map(|_| ()))
}

/// Refuses explicit particles and bonds whose storage exceeds `limit`, placed at the
/// first particle (bonds left out) or else the first bond whose count crosses it.
pub(super) fn check_counts(
    plans: &[Plan],
    ps: &[RawParticle],
    bonds: &[RawBond],
    limit: usize,
) -> Result<(), Issue> {
    let (n, b) = (ps.len(), bonds.len());
    let Err(e) = fits(plans, n, b, limit) else {
        return Ok(());
    };
    let first = (1..=n)
        .map(|k| (k, 0))
        .chain((1..=b).map(|l| (n, l)))
        .find(|&(k, l)| fits(plans, k, l, limit).is_err());
    let span = match first {
        Some((_, l)) if l > 0 => bonds[l - 1].between.span(),
        Some((k, _)) => ps[k - 1].position.span(),
        None => ps[n.saturating_sub(1)].position.span(),
    };
    Err(too_large(span, e))
}
