//! A step that the kernel refuses is retried before the run gives up.
//!
//! At temperature the unconstrained move carries a random kick of size `sqrt(dt)`; on
//! rare steps it is so large, for the chain's local shape, that the projection along
//! the start-of-step bond vectors has no solution near the start (the constraint
//! solvers then fail, each in its own way; `docs/BROWNIAN.md`, "A refused step").
//! Without noise the same happens where the step is long for the geometry: a jammed
//! pile whose contacts turn far within one step (`docs/CONTACTS.md`). Such a step is
//! retried as 2, then 4, ... up to `2^MAX_DEPTH` shorter steps; at temperature their
//! noise refines the refused step's (a Brownian bridge, the kernel's
//! [`Noise::split`]): the sub-steps' increments add up to the refused one, so the
//! retry does not bias the run against large kicks. Only when the deepest split fails
//! too does the run stop, with the state and the generator as they were before the
//! step (and the last checkpoint kept). A step the kernel accepts is never split, so a
//! run that needs no retry keeps its bits.

use hydrorattle::{ExternalForce, Noise, Params, Real, StepError, StepReport, Workspace};

use super::Beads;
use super::lanczos::LanczosTally;

/// Deepest split tried: a refused step is retried as at most `2^MAX_DEPTH` sub-steps.
/// Seven halvings (128 sub-steps): a jammed pile at rest, stepped 100 times longer than
/// its settling time, has its unconstrained move carry every sphere 100 radii through
/// the wall, and the contact solve diverges from there; it passes from about 2.5 time
/// units down (a step of 100 in 64 sub-steps). The shallower depths are tried first,
/// so a step that passed at 16 sub-steps or fewer passes as before, bit for bit; only a
/// step that would have ended the run is tried further.
pub const MAX_DEPTH: u8 = 7;

/// Steps the run retried, and the sub-steps they took in the end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Retries {
    /// Steps refused at full length and completed as split steps.
    pub steps: u64,
    /// Sub-steps those steps took (`2^depth` each, the depth that succeeded).
    pub substeps: u64,
}

/// What a run counts over its steps: the steps retried split and, at temperature, the
/// noise's Lanczos iterations of every kernel step (full or sub-step, refused or not).
pub struct Counters<'a> {
    /// Steps retried split.
    pub retries: &'a mut Retries,
    /// The noise's square root.
    pub lanczos: &'a mut LanczosTally,
}

/// One step of `p` from `beads`, drawing from `noise`; a step the kernel refuses is
/// retried split (see the module). On error the state and `noise` are as
/// they were.
pub fn step<T: Real, E: ExternalForce<T>>(
    beads: &mut Beads<T>,
    bonds: &[hydrorattle::Bond<T>],
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
    noise: &mut Noise,
    counters: Counters<'_>,
) -> Result<StepReport<T>, StepError> {
    let Counters { retries, lanczos } = counters;
    let thermal = p.brownian.is_some_and(|b| b.temperature > T::ZERO);
    let mut state = beads.state();
    state.noise = Some(noise);
    let outcome = hydrorattle::step_slices(state, bonds, p, ws, ext);
    if thermal {
        lanczos.add(&outcome);
    }
    let refused = match outcome {
        Ok(r) => return Ok(r),
        Err(e) => e,
    };
    if !retryable(&refused) {
        return Err(refused);
    }
    let start = beads.clone();
    for depth in 1..=MAX_DEPTH {
        let parts = 1u32 << depth;
        let mut q = *p;
        q.dt = p.dt / T::from_f64(f64::from(parts));
        let mut report = StepReport::<T>::default();
        let mut last = None;
        for index in 0..parts {
            let mut g = noise.split(depth, index);
            let mut state = beads.state();
            state.noise = Some(&mut g);
            let outcome = hydrorattle::step_slices(state, bonds, &q, ws, ext);
            if thermal {
                lanczos.add(&outcome);
            }
            match outcome {
                Ok(r) => {
                    // Work adds up; the state's figures are the last sub-step's.
                    report.iterations += r.iterations;
                    report.velocity_iterations += r.velocity_iterations;
                    report.contact_rounds += r.contact_rounds;
                    report.noise_iterations += r.noise_iterations;
                    report.max_tension = report.max_tension.max(r.max_tension);
                    report.residual = r.residual;
                    report.contacts = r.contacts;
                    report.wall_contacts = r.wall_contacts;
                    last = Some(g);
                }
                Err(e) => {
                    log::debug!("split step {index} of {parts} refused: {e}");
                    last = None;
                    break;
                }
            }
        }
        match last {
            Some(g) => {
                log::debug!("step at t = {} done as {parts} sub-steps", start.time);
                *noise = g.join();
                // The time the unsplit step would have reached, bit for bit.
                beads.time = start.time + p.dt;
                retries.steps += 1;
                retries.substeps += u64::from(parts);
                return Ok(report);
            }
            None => beads.clone_from(&start),
        }
    }
    Err(refused)
}

/// Failures of the step itself, which a shorter step can avoid (not bad input).
fn retryable(e: &StepError) -> bool {
    matches!(
        e,
        StepError::NoConvergence { .. }
            | StepError::Linalg { .. }
            | StepError::Degenerate { .. }
            | StepError::NonFinite { .. }
            | StepError::Overlap { .. }
            | StepError::Particle(_)
            | StepError::Bond(hydrorattle::BondError::Overstretched { .. })
    )
}
