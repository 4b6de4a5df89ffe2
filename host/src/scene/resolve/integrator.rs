//! The `[integrator]` table: its defaults, its numbers' bounds, and the checks that
//! set the step against the rest of the scene (FENE's extension in the run's precision,
//! the ambient rotation a step may follow). Apart because the body's sizing
//! (`body.rs`) needs the resolved step count too, and a suspension resolves it again.

use crate::scene::error::{Issue, issue};
use crate::scene::raw::{Bound, RawIntegrator, RawScene, number};
use crate::scene::{Flow, Integrator, MAX_ITERATIONS, Method, Precision};

pub(super) fn resolve_integrator(r: &RawIntegrator) -> Result<Integrator, Issue> {
    let dt = number(&Some(r.dt.clone()), 0.0, "dt", Bound::Positive)?;
    let duration = number(&Some(r.duration.clone()), 0.0, "duration", Bound::Positive)?;
    if dt > duration {
        return Err(issue(
            r.dt.span(),
            format!("dt ({dt}) is longer than the duration ({duration})"),
        ));
    }
    if duration / dt > 1e12 {
        return Err(issue(
            r.duration.span(),
            format!("duration / dt = {:e} steps is too many", duration / dt),
        ));
    }
    let max_iterations = match &r.max_iterations {
        None => 500,
        Some(m) if *m.get_ref() == 0 => {
            return Err(issue(m.span(), "max_iterations must be >= 1"));
        }
        Some(m) if *m.get_ref() > MAX_ITERATIONS => {
            return Err(issue(
                m.span(),
                format!(
                    "max_iterations must be at most {} (it bounds one step's constraint work)",
                    MAX_ITERATIONS
                ),
            ));
        }
        Some(m) => *m.get_ref(),
    };
    Ok(Integrator {
        method: r.method.0,
        dt,
        duration,
        solver: r.solver.map_or_else(Default::default, |s| s.0),
        tolerance: number(&r.tolerance, 1e-10, "tolerance", Bound::Positive)?,
        max_iterations,
        precision: r.precision.unwrap_or_default(),
        stiffness: number(&r.stiffness, 1e4, "stiffness", Bound::Positive)?,
        fene: resolve_fene(r)?,
        matrix_free: r.matrix_free.as_ref().is_some_and(|m| *m.get_ref()),
        compact_products: r.compact_products.unwrap_or(false),
    })
}

/// `fene` (the FENE springs' maximum extension): > 0 and finite, springs only.
fn resolve_fene(r: &RawIntegrator) -> Result<Option<f64>, Issue> {
    let Some(q0) = &r.fene else {
        return Ok(None);
    };
    if r.method.0 != Method::Springs {
        return Err(issue(
            q0.span(),
            "fene (the FENE springs' maximum extension) needs method = \"springs\"",
        ));
    }
    let q = number(&r.fene, 0.0, "fene (maximum extension)", Bound::Positive)?;
    // The kernel squares it in the run's precision.
    let usable = match r.precision.unwrap_or_default() {
        Precision::F32 => {
            let q = q as f32;
            q > 0.0 && (q * q).is_normal()
        }
        Precision::F64 => (q * q).is_normal(),
    };
    if !usable {
        return Err(issue(
            q0.span(),
            format!(
                "fene {} is not usable in the run's precision (its square must be a normal number)",
                crate::output::format_f64(q)
            ),
        ));
    }
    Ok(Some(q))
}

/// The most the ambient rotation may turn the scene in one step, radians. The flow's
/// velocity `Omega x r` enters every method explicitly, so a step grows a radius about
/// the axis by `sqrt(1 + (|Omega| dt)^2)` (first order; Heun's is no better there): past
/// one radian a step no longer follows the rotation at all, and the run spirals out
/// until its precision overflows (vorticity 100 at dt 0.1 grew the radius
/// tenfold a step). Refused at the `vorticity` line instead.
pub const MAX_TURN_PER_STEP: f64 = 1.0;

pub(super) fn check_turn(raw: &RawScene, flow: &Flow, dt: f64) -> Result<(), Issue> {
    let w = flow.vorticity;
    let rate = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let turn = rate * dt;
    match raw.flow.as_ref().and_then(|f| f.vorticity.as_ref()) {
        Some(v) if turn > MAX_TURN_PER_STEP => Err(issue(
            v.span(),
            format!(
                "vorticity turns the scene by {turn} rad per step (|vorticity| {rate} x dt {dt}), \
                 more than {MAX_TURN_PER_STEP}: no method here follows a rotation that fast; \
                 use dt <= {}",
                MAX_TURN_PER_STEP / rate
            ),
        )),
        _ => Ok(()),
    }
}
