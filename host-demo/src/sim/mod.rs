//! Runs a scene on the kernel: the precision dispatch, the time loop, observables,
//! outcome, and the files of a run (`trajectory.xyz`, `observables.csv`,
//! `summary.json`), each written to a temporary name and renamed.
//!
//! The state lives in vectors of any length ([`Beads`]), stepped by the kernel's
//! `step_slices` in storage sized for the scene's method, rotation flag, solver and
//! bead count ([`Plan`]), under a storage limit checked before anything is built.

mod beads;
mod record;

pub use beads::{Beads, BuildError, bonds};
pub use record::{COLUMNS, Observables};

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use hydrorattle::observables::{self, Thresholds, Twist};
use hydrorattle::{
    Buffers, Hydro, Noise, Params, Real, SoftContact, Solver as KSolver, step_slices_thermal,
};
use serde::Serialize;

use crate::output::write_json;
use crate::progress::Progress;
use crate::render::Snapshot;
use crate::scene::{DEFAULT_SEED, Hydrodynamics, Precision, Scene};
use crate::sizing::{DEFAULT_LIMIT, Plan, TooLarge};
use record::Recorder;

/// What `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Scene name (file stem or case).
    pub scene: String,
    /// Number of particles.
    pub particles: usize,
    /// Number of bonds.
    pub bonds: usize,
    /// The model as run.
    pub model: crate::scene::Model,
    /// The integrator as run.
    pub integrator: crate::scene::Integrator,
    /// Constraint tolerance actually used (raised to what the precision can reach).
    pub tolerance_used: f64,
    /// Contact stiffness (0 when off).
    pub contact_stiffness: f64,
    /// Steps asked for.
    pub steps: usize,
    /// Steps completed (fewer than `steps` when the run failed).
    pub steps_done: usize,
    /// Wall time of the time loop, seconds.
    pub wall_time_s: f64,
    /// Steps per second.
    pub steps_per_second: f64,
    /// Mean constraint iterations per step.
    pub mean_iterations: f64,
    /// Observables at the end.
    pub final_observables: Observables,
    /// Late-time twist rate (slope over the last quarter of the run), rad per time unit.
    pub twist_rate: f64,
    /// Classified outcome: stretched, twisting, other (or failed).
    pub outcome: String,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// What `level = "auto"` chose and why (None for a manual level).
    pub level_choice: Option<crate::auto::Choice>,
}

/// A finished run: summary, first and last configurations, the observables series.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Summary.
    pub summary: Summary,
    /// Initial configuration.
    pub initial: Snapshot,
    /// Final configuration.
    pub last: Snapshot,
    /// Observables every `output.every` steps.
    pub series: Vec<Observables>,
}

/// Options of a run.
#[derive(Debug, Clone, Copy)]
pub struct RunOptions {
    /// Show a progress bar (on a terminal, after a second).
    pub progress: bool,
    /// Stop after at most this many steps (smoke runs); None: the whole duration.
    pub max_steps: Option<usize>,
    /// Largest step storage allowed, bytes.
    pub max_storage: usize,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            progress: false,
            max_steps: None,
            max_storage: DEFAULT_LIMIT,
        }
    }
}

/// Runs `scene`, writing the run's files into `out` when given. Refuses (before
/// writing anything) a scene whose step storage would exceed `opts.max_storage`.
pub fn run(scene: &Scene, name: &str, out: Option<&Path>, opts: RunOptions) -> Result<RunResult> {
    let choice =
        (scene.model.level == crate::scene::Level::Auto).then(|| crate::auto::choose(scene));
    let scene = match &choice {
        Some(c) => {
            log::info!("{name}: level auto: {}", c.reason);
            crate::auto::apply(scene, c)
        }
        None => scene.clone(),
    };
    match scene.integrator.precision {
        Precision::F64 => run_t::<f64>(&scene, name, out, opts, choice),
        Precision::F32 => run_t::<f32>(&scene, name, out, opts, choice),
    }
}

/// Kernel parameters for a scene in precision `T`.
pub fn params<T: Real>(scene: &Scene) -> Params<T> {
    let i = &scene.integrator;
    let mut p = Params::new(T::from_f64(i.dt));
    p.viscosity = T::from_f64(scene.fluid.viscosity);
    p.fluid_density = T::from_f64(scene.fluid.density);
    p.gravity = T::v3_from(scene.gravity);
    p.flow_velocity = T::v3_from(scene.flow.velocity);
    p.vorticity = T::v3_from(scene.flow.vorticity);
    p.hydro = match scene.model.hydrodynamics {
        Hydrodynamics::Rpy => Hydro::Rpy,
        Hydrodynamics::Oseen => Hydro::Oseen,
        Hydrodynamics::FreeDraining => Hydro::FreeDraining,
    };
    p.method = i.method.kernel();
    p.rotation = scene.model.rotation;
    // f32 cannot reach 1e-10: floor the tolerance at a few hundred ulps.
    let floor = 256.0 * T::EPSILON.to_f64();
    p.solver = KSolver {
        kind: i.solver.kind(),
        tolerance: T::from_f64(i.tolerance.max(floor)),
        max_iterations: u32::try_from(i.max_iterations).unwrap_or(u32::MAX),
    };
    p.allow_overlap = scene.model.overlap == crate::scene::Overlap::Allow;
    p.spring_stiffness = T::from_f64(i.stiffness);
    // The paper's explicit drag can shiver silently (bounded, wrong) beyond its limit:
    // the demo refuses such steps up front.
    p.stability_guard = true;
    p.brownian = scene.brownian.map(|b| hydrorattle::Brownian {
        temperature: T::from_f64(b.temperature),
        drift: b.drift.kernel(),
    });
    p
}

fn snapshot<T: Real>(ps: &[T::V3], radius: &[T], time: T) -> Snapshot {
    Snapshot {
        time: time.to_f64(),
        positions: ps.iter().map(|&v| T::v3_to_f64(v)).collect(),
        radii: radius.iter().map(|r| r.to_f64()).collect(),
    }
}

/// Least-squares slope of `y` against `x`.
pub fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    if points.len() < 2 {
        return 0.0;
    }
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = points.iter().fold((0.0, 0.0), |a, p| {
        (a.0 + (p.0 - mx) * (p.1 - my), a.1 + (p.0 - mx) * (p.0 - mx))
    });
    if den > 0.0 { num / den } else { 0.0 }
}

/// What a run steps: its particles, bonds and storage.
struct Prepared<T: Real> {
    beads: Beads<T>,
    bonds: Vec<hydrorattle::Bond<T>>,
    store: Buffers<T>,
}

/// The particles, bonds and storage of a run, checked before anything is written.
fn prepare<T: Real>(scene: &Scene, p: &Params<T>, limit: usize) -> Result<Prepared<T>, BuildError> {
    let (n, b) = (scene.particles.len(), scene.bonds.len());
    // Sized first: an oversized scene is refused before any O(N^2) work.
    let layout = Plan::of(scene).check(n, b, limit)?;
    // Thermal noise needs the mobility's factor on top (`Layout::thermal`).
    let layout = match scene.brownian {
        Some(_) => {
            let l = layout.thermal(p.method, n, b);
            let bytes = l.bytes::<T>();
            if bytes > limit {
                return Err(TooLarge {
                    particles: n,
                    bonds: b,
                    bytes: Some(bytes),
                    limit,
                }
                .into());
            }
            l
        }
        None => layout,
    };
    let beads = Beads::<T>::new(&scene.particles, 1.0)?;
    beads.check_pairs(p.allow_overlap)?;
    Ok(Prepared {
        bonds: bonds::<T>(&scene.bonds, n)?,
        beads,
        store: Buffers::try_new(layout)
            .map_err(|_| BuildError::OutOfMemory(layout.bytes::<T>()))?,
    })
}

fn run_t<T: Real>(
    scene: &Scene,
    name: &str,
    out: Option<&Path>,
    opts: RunOptions,
    level_choice: Option<crate::auto::Choice>,
) -> Result<RunResult> {
    let p = params::<T>(scene);
    let Prepared {
        mut beads,
        bonds,
        mut store,
    } = prepare::<T>(scene, &p, opts.max_storage)?;
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let mut ws = store.workspace();
    let mut noise = Noise::new(scene.brownian.map_or(DEFAULT_SEED, |b| b.seed));
    let contact = scene.contact.map(|k| SoftContact {
        stiffness: T::from_f64(k),
    });
    let mut ext = |pos: &[T::V3], radius: &[T], force: &mut [T::V3]| {
        if let Some(mut c) = contact {
            hydrorattle::ExternalForce::add(&mut c, pos, radius, force);
        }
    };
    let steps = opts.max_steps.map_or(scene.integrator.steps(), |m| {
        m.min(scene.integrator.steps())
    });
    let every = scene.output.every.max(1);
    let mut rec = Recorder::new(out, scene.species())?;
    let mut twist_prev = vec![T::ZERO; beads.len()];
    let mut twist = Twist::new(&mut twist_prev, T::from_f64(0.25));
    let mut series = Vec::with_capacity(steps / every + 2);
    let observe = |beads: &Beads<T>, twist: T, iterations: u32, tension: T| {
        Observables::of(beads, &bonds, p.gravity, twist, iterations, tension)
    };
    let initial = snapshot::<T>(&beads.pos, &beads.radius, beads.time);
    twist.update(&beads.pos, p.gravity);
    let first = observe(&beads, T::ZERO, 0, T::ZERO);
    rec.record(&beads, &first)?;
    series.push(first);
    let bar = if opts.progress {
        Progress::new(steps as u64, name)
    } else {
        Progress::hidden(steps as u64)
    };
    let start = Instant::now();
    let (mut done, mut failure, mut total_iterations) = (0usize, None, 0u64);
    for s in 1..=steps {
        match step_slices_thermal(beads.state(), &bonds, &p, &mut ws, &mut ext, &mut noise) {
            Ok(rep) => {
                done = s;
                total_iterations += u64::from(rep.iterations);
                let tw = twist.update(&beads.pos, p.gravity);
                if s % every == 0 || s == steps {
                    let o = observe(&beads, tw, rep.iterations, rep.max_tension);
                    rec.record(&beads, &o)?;
                    series.push(o);
                }
            }
            Err(e) => {
                log::warn!("{name}: step {s} failed at t = {}: {e}", beads.time);
                failure = Some(format!("step {s} (t = {}): {e}", beads.time.to_f64()));
                break;
            }
        }
        if s % 256 == 0 {
            bar.set_position(s as u64);
        }
    }
    bar.finish();
    let wall = start.elapsed().as_secs_f64();
    // Close the state: a final row when the run stopped between frames.
    let last_obs = observe(&beads, twist.total, 0, T::ZERO);
    if series.last().map(|o| o.time) != Some(last_obs.time) {
        rec.record(&beads, &last_obs)?;
        series.push(last_obs);
    }
    let tail: Vec<(f64, f64)> = series[series.len() * 3 / 4..]
        .iter()
        .map(|o| (o.time, o.twist))
        .collect();
    let twist_rate = slope(&tail);
    let th = Thresholds::<f64>::default();
    let outcome = match failure {
        Some(_) => "failed".to_string(),
        None => observables::classify(last_obs.verticality, last_obs.extension, twist_rate, &th)
            .name()
            .to_string(),
    };
    let summary = Summary {
        scene: name.to_string(),
        particles: beads.len(),
        bonds: bonds.len(),
        model: scene.model,
        integrator: scene.integrator,
        tolerance_used: p.solver.tolerance.to_f64(),
        contact_stiffness: scene.contact.unwrap_or(0.0),
        steps,
        steps_done: done,
        wall_time_s: wall,
        steps_per_second: done as f64 / wall.max(1e-12),
        mean_iterations: total_iterations as f64 / (done.max(1) as f64),
        final_observables: last_obs,
        twist_rate,
        outcome,
        failure,
        level_choice,
    };
    rec.commit()?;
    if let Some(dir) = out {
        write_json(&dir.join("summary.json"), &summary)?;
    }
    Ok(RunResult {
        summary,
        initial,
        last: snapshot::<T>(&beads.pos, &beads.radius, beads.time),
        series,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Method, Solver};
    use hydrorattle::Layout;

    #[test]
    fn the_storage_checked_is_the_storage_the_kernel_asks_for() {
        let mut scene = Scene::figure1().unwrap().remove(0).1;
        for method in Method::ALL {
            for solver in [Solver::Auto, Solver::Sweep, Solver::Newton, Solver::Krylov] {
                for rotation in [false, true] {
                    scene.integrator.method = method;
                    scene.integrator.solver = solver;
                    scene.model.rotation = rotation;
                    let (n, b) = (scene.particles.len(), scene.bonds.len());
                    let want = Layout::for_params(&params::<f64>(&scene), n, b);
                    assert_eq!(Plan::of(&scene).layout(n, b), Some(want));
                }
            }
        }
    }
}
