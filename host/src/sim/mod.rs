//! Runs a scene on the kernel: the precision dispatch, the time loop, observables,
//! outcome, checkpoints, and the files of a run, each written to a temporary name and
//! renamed:
//!
//! * `trajectory.xyz` (extended XYZ, exact) and `trajectory.gsd` (GSD, HOOMD's format,
//!   with types and bonds), one frame every `output.every` steps;
//! * `observables.csv`, one row per frame; its last row is `summary.json`'s
//!   `final_observables`;
//! * `summary.json`: the run's record (resolved scene, code version, machine, results);
//! * `scene.toml`: the resolved scene, which re-runs to the same result;
//! * `checkpoint.json` with `--checkpoint-every` ([`Checkpoint`]).
//!
//! Everything is streamed: memory does not grow with the duration. The state lives in
//! vectors of any length ([`Beads`]), held with the bonds, parameters and storage by an
//! [`Engine`], whose `step` is the one call of the kernel's step in the host code
//! (storage sized for the scene's method, rotation flag, solver and bead count by
//! [`Plan`](crate::sizing::Plan), under a storage limit checked before anything is
//! built). The run itself is a short list of stages (`run_loop.rs`); the CLI's `run`
//! and the Python package call it through [`run_scene_file`].

mod any;
mod checkpoint;
mod columns;
mod engine;
mod frames;
mod lanczos;
mod record;
pub mod retry;
mod run_loop;
mod saved;
#[cfg(test)]
mod saved_tests;
pub mod stop;
mod tail;

pub use crate::scene::{Beads, BuildError, beads, bonds, params};
pub use any::AnyEngine;
pub use checkpoint::{CHECKPOINT, Checkpoint, NoCheckpoint, StepSolve};
pub use columns::{ColumnsMismatch, check_columns};
pub use engine::{Engine, Extra};
pub use frames::{KeepFrames, MAX_FRAME_BEADS, MAX_FRAMES, step_at_or_after};
pub use lanczos::{LanczosTally, NoiseIterations};
pub use record::{
    COLUMNS, Label, Marks, NEAR_VERTICAL_COS, OBSERVABLES_CSV, Observables, TRAJECTORY_GSD,
    TRAJECTORY_XYZ,
};
pub use saved::{Saved, SavedParams};
pub use stop::{Interrupted, Stop};

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use hydrorattle::Real;
use serde::Serialize;

use crate::provenance::{CODE_VERSION, Machine};
use crate::scene::{Flow, Fluid, Precision, Scene};
use crate::sizing::{DEFAULT_LIMIT, Limits};
pub use frames::Snapshot;

/// The resolved scene's copy in the output folder.
pub const SCENE_TOML: &str = "scene.toml";
/// The run's record in the output folder.
pub const SUMMARY_JSON: &str = "summary.json";

/// What `summary.json` holds: everything needed to rerun, and the results.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Scene name (file stem or case).
    pub scene: String,
    /// The scene file's path as given, when the run came from a file.
    pub scene_path: Option<String>,
    /// The code version (`git describe` at build time).
    pub code_version: String,
    /// The machine the run ran on.
    pub machine: Machine,
    /// Kernel precision.
    pub precision: Precision,
    /// The fluid.
    pub fluid: Fluid,
    /// Gravitational acceleration.
    pub gravity: [f64; 3],
    /// The ambient flow.
    pub flow: Flow,
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
    /// The simulated time the run was resumed from, if it was.
    pub resumed_from: Option<f64>,
    /// Wall time of the time loop, seconds.
    pub wall_time_s: f64,
    /// Steps per second (of the steps this invocation made).
    pub steps_per_second: f64,
    /// Mean constraint iterations per step.
    pub mean_iterations: f64,
    /// Observables at the end: the last row of `observables.csv`.
    pub final_observables: Observables,
    /// Late-time twist rate (slope over the last quarter of the run's time), rad per
    /// time unit.
    pub twist_rate: f64,
    /// Late state: the named state of most frames in the last quarter of the run's time
    /// (`observables::FrameState` names), or "failed".
    pub outcome: String,
    /// The order in which the bonds first turned near-vertical (the stretching front).
    pub front: Front,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// Steps the kernel refused and the run completed as split steps.
    pub retries: retry::Retries,
    /// At temperature: the Lanczos iterations of the noise's square root per kernel
    /// step (absent for a run without noise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_iterations: Option<NoiseIterations>,
    /// With `[free_space] reweigh`: the steps taken on the pair sums in place of the
    /// fast product (`scene::free_reweigh`); absent for a run that does not weigh.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair_sum_steps: Option<u64>,
    /// With a wall: the landing time, the end of the first step after which a sphere
    /// is held on the wall (`StepReport::wall_contacts > 0`: the first contact);
    /// `None` without a wall or before any sphere touches it.
    pub landing_time: Option<f64>,
    /// What `level = "auto"` chose and why (None for a manual level).
    pub level_choice: Option<crate::auto::Choice>,
    /// The scene as run: every default filled in and the `auto` choice applied
    /// (`scene.toml` holds the same as a scene file).
    pub resolved_scene: Scene,
    /// The data files as the run finished them (size and digest, by name), for a
    /// reader to check that they are still those; last, the fields above unchanged.
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub files: std::collections::BTreeMap<String, crate::output::FileCheck>,
}

impl Summary {
    /// The record of `scene` before any step: results empty.
    pub fn for_scene(scene: &Scene, name: &str) -> Summary {
        Summary {
            scene: name.to_string(),
            scene_path: None,
            code_version: CODE_VERSION.to_string(),
            machine: Machine::this(),
            precision: scene.integrator.precision,
            fluid: scene.fluid,
            gravity: scene.gravity,
            flow: scene.flow,
            particles: scene.particles.len(),
            bonds: scene.bonds.len(),
            model: scene.model,
            integrator: scene.integrator,
            tolerance_used: scene.integrator.tolerance,
            contact_stiffness: scene.contact.map_or(0.0, |c| c.stiffness()),
            steps: scene.integrator.steps(),
            steps_done: 0,
            resumed_from: None,
            wall_time_s: 0.0,
            steps_per_second: 0.0,
            mean_iterations: 0.0,
            final_observables: Observables::default(),
            twist_rate: 0.0,
            outcome: String::new(),
            front: Front::default(),
            failure: None,
            retries: retry::Retries::default(),
            noise_iterations: None,
            pair_sum_steps: None,
            landing_time: None,
            level_choice: None,
            resolved_scene: scene.clone(),
            files: Default::default(),
        }
    }
}

/// The order in which bonds first turned near-vertical (checked after every step).
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Front {
    /// A bond is near-vertical when `|cos|` of its angle with gravity is at least this.
    pub cos_min: f64,
    /// Bonds that turned near-vertical at some time.
    pub count: usize,
    /// Correlation between bond index (bond 0 at the head) and first-vertical time:
    /// +1 for a front from the head to the end, -1 the other way, 0 without order.
    pub correlation: f64,
    /// Per bond, in bond order, the first time it was near-vertical (None: never).
    pub first_vertical: Vec<Option<f64>>,
}

/// A finished run: summary, first and last configurations, the observables series.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Summary.
    pub summary: Summary,
    /// Initial configuration (of this invocation: the checkpoint's for a resumed run).
    pub initial: Snapshot,
    /// Final configuration.
    pub last: Snapshot,
    /// Observables every `output.every` steps (empty unless
    /// [`RunOptions::keep_series`]).
    pub series: Vec<Observables>,
    /// Configurations at the cadence of [`RunOptions::keep`] (empty by default).
    pub frames: Vec<Snapshot>,
    /// Configurations at the times of [`RunOptions::keep`], in the order asked (None
    /// for a time past the run's last step).
    pub at: Vec<Option<Snapshot>>,
}

/// Options of a run.
#[derive(Debug, Clone, Copy)]
pub struct RunOptions<'a> {
    /// Show a progress bar (on a terminal, after a second).
    pub progress: bool,
    /// Stop after at most this many steps (smoke runs); None: the whole duration.
    pub max_steps: Option<usize>,
    /// Largest step storage allowed, bytes.
    pub max_storage: usize,
    /// Keep the observables series in memory ([`RunResult::series`]); off, memory does
    /// not grow with the duration (the files have every row).
    pub keep_series: bool,
    /// Write a checkpoint every this much simulated time (rounded to whole steps), when
    /// the run writes files.
    pub checkpoint_every: Option<f64>,
    /// Configurations to keep in memory for pictures (none by default).
    pub keep: KeepFrames<'a>,
    /// Threads for the mobility's bands from [`hydrorattle::parallel::BANDED_MIN`] beads
    /// on (smaller scenes run on the calling thread); 0: every core. The bits do not
    /// depend on it.
    pub threads: usize,
    /// Stop between steps when asked ([`Stop`]): a checkpoint, then [`Interrupted`].
    pub stop: Stop,
}

impl Default for RunOptions<'_> {
    fn default() -> Self {
        RunOptions {
            progress: false,
            max_steps: None,
            max_storage: DEFAULT_LIMIT,
            keep_series: true,
            checkpoint_every: None,
            keep: KeepFrames::default(),
            threads: 0,
            stop: Stop::default(),
        }
    }
}

impl RunOptions<'static> {
    /// The options of a run into files, as the CLI makes them: nothing kept in memory.
    pub fn files(limits: Limits, checkpoint_every: Option<f64>, progress: bool) -> Self {
        RunOptions {
            progress,
            max_storage: limits.storage,
            keep_series: false,
            checkpoint_every,
            ..RunOptions::default()
        }
    }
}

/// Runs `scene`, writing the run's files into `out` when given. Refuses (before
/// writing anything) a scene whose step storage would exceed `opts.max_storage`.
pub fn run(scene: &Scene, name: &str, out: Option<&Path>, opts: RunOptions) -> Result<RunResult> {
    run_from(scene, name, out, opts, Start::default())
}

/// Where a run comes from, for its record, and where it starts.
#[derive(Debug, Clone, Default)]
pub struct Start {
    /// The scene file, when the run came from one.
    pub scene_path: Option<PathBuf>,
    /// The checkpoint to continue from.
    pub checkpoint: Option<Checkpoint>,
    /// The caller holds the output folder's [`FolderLock`](crate::output::FolderLock)
    /// (a sweep locks a point before it looks at its files); otherwise the run takes
    /// it, and refuses a folder another process writes with a
    /// [`Locked`](crate::output::Locked).
    pub locked: bool,
}

/// [`run`] from `start`. A run that fails before its files are complete removes the
/// output folder if it created it (and leaves no `*.tmp` in any case).
pub fn run_from(
    scene: &Scene,
    name: &str,
    out: Option<&Path>,
    opts: RunOptions,
    start: Start,
) -> Result<RunResult> {
    let origin = start.scene_path.as_ref().map(|p| p.display().to_string());
    scene.check_box_runs(origin.as_deref())?;
    let (scene, choice) = resolve_level(scene, name);
    let fresh = out.filter(|d| !d.exists());
    let origin = run_loop::Origin {
        scene_path: start.scene_path.map(|p| p.display().to_string()),
        level_choice: choice,
        checkpoint: start.checkpoint.as_ref(),
        locked: start.locked,
    };
    let result = AnyEngine::new(&scene, opts.max_storage)
        .map_err(anyhow::Error::from)
        .and_then(|engine| {
            crate::each_engine!(engine, e, _T => run_loop::run_t(e, &scene, name, out, opts, origin))
        });
    // A folder another process locked is that process's, even one created since; a
    // run stopped on request keeps its files for the rerun.
    let theirs = |e: &anyhow::Error| {
        e.downcast_ref::<crate::output::Locked>().is_some()
            || e.downcast_ref::<Interrupted>().is_some()
    };
    if result.as_ref().is_err_and(|e| !theirs(e))
        && let Some(dir) = fresh.filter(|d| d.exists())
    {
        let _ = std::fs::remove_dir_all(dir);
    }
    result
}

/// `scene` with `level = "auto"` applied (and what was chosen), or as it is; its box's
/// `method = "auto"` resolved too ([`crate::scene::BoxMethod::resolve`]), and free
/// space's (`Scene::with_free_resolved`), so that the run's `scene.toml` names the
/// path it ran.
pub fn resolve_level(scene: &Scene, name: &str) -> (Scene, Option<crate::auto::Choice>) {
    let scene = scene.clone().with_box_resolved().with_free_resolved();
    if scene.model.level != crate::scene::Level::Auto {
        return (scene, None);
    }
    let c = crate::auto::choose(&scene);
    log::info!("{name}: level auto: {}", c.reason);
    (crate::auto::apply(&scene, &c), Some(c))
}

/// What `host-demo run SCENE --out OUT` does: reads the scene file under `limits` and
/// runs it into `out` (named after the file). The CLI and the Python package
/// (`hydrorattle.run_scene`) both call this; the run draws nothing (the CLI draws the
/// pictures after it, from the result).
pub fn run_scene_file(
    scene_path: &Path,
    out: &Path,
    limits: Limits,
    checkpoint_every: Option<f64>,
    progress: bool,
    threads: usize,
) -> Result<RunResult> {
    let opts = RunOptions {
        threads,
        ..RunOptions::files(limits, checkpoint_every, progress)
    };
    run_scene_file_with(scene_path, out, limits, opts)
}

/// [`run_scene_file`] with the run's options (a stop request, threads, checkpoints).
pub fn run_scene_file_with(
    scene_path: &Path,
    out: &Path,
    limits: Limits,
    opts: RunOptions,
) -> Result<RunResult> {
    let scene = Scene::from_path_limited(scene_path, limits)?;
    log::info!(
        "scene: {} particles, {} bonds, {:?}, {} steps",
        scene.particles.len(),
        scene.bonds.len(),
        scene.integrator.method,
        scene.integrator.steps()
    );
    let name = scene_name(scene_path);
    let start = Start {
        scene_path: Some(scene_path.to_path_buf()),
        checkpoint: None,
        locked: false,
    };
    run_from(&scene, &name, Some(out), opts, start)
}

/// A run's name from its scene file: the file stem.
pub fn scene_name(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".to_string(), |s| s.to_string_lossy().into_owned())
}

/// Continues the run whose files are in `dir` from its checkpoint to simulated time
/// `until`, under `limits`: the files are cut back to the checkpoint and continued, the
/// summary and `scene.toml` rewritten (with the new duration). `until` may be the
/// checkpoint's own time: a run killed after its last checkpoint (taken on its last
/// step) is finished there, its closing row written as the uninterrupted run wrote it. The scene to `until` is
/// read under `limits` as `run` reads a scene file (storage, output size, step count).
/// A folder without a checkpoint is refused with a [`NoCheckpoint`], and a run whose
/// `observables.csv` has other columns than this program's (another version's) with a
/// [`ColumnsMismatch`], both before anything is written.
pub fn resume(dir: &Path, until: f64, limits: Limits, opts: RunOptions) -> Result<RunResult> {
    let checkpoint = Checkpoint::load(dir)?;
    let rows = dir.join(OBSERVABLES_CSV);
    check_columns(&crate::output::continued_source(
        &rows,
        checkpoint.marks.csv_bytes,
    ))?;
    let scene_path = dir.join(SCENE_TOML);
    // The output limit is the resumed run's, checked below at its own duration.
    let unlimited = Limits {
        output: u64::MAX,
        ..limits
    };
    let mut scene = Scene::from_path_limited(&scene_path, unlimited)?;
    let at = checkpoint.time();
    let dt = scene.integrator.dt;
    // Compared in whole steps below (the checkpoint's time is a sum of steps, a few
    // ulps off the multiple of dt that `until` names). Times print as `{:?}`: 1e300
    // as `1e300`, not as its 301 digits.
    if !(until.is_finite() && until > 0.0) {
        bail!("--until {until:?} must be a time at or after the checkpoint's t = {at:?}");
    }
    if checkpoint.precision != scene.integrator.precision {
        bail!(
            "{}: the checkpoint's precision differs from {}",
            dir.join(CHECKPOINT).display(),
            scene_path.display()
        );
    }
    scene.integrator.duration = until;
    // The scene as `run` would read it (the same checks, by the same reader): the text
    // is `scene.toml`'s own, as this program writes it, with the new duration.
    let origin = scene_path.display().to_string();
    let scene = Scene::parse_limited(&scene.to_toml(), &origin, limits)
        .with_context(|| format!("resuming to --until {until:?}"))?;
    let steps = scene.integrator.steps() as u64;
    if steps < checkpoint.step {
        bail!(
            "--until {until:?} must be a time at or after the checkpoint's t = {at:?} (step {} of dt = {dt:?})",
            checkpoint.step
        );
    }
    // Ending at the checkpoint's step: its closing row is written from the solve the
    // checkpoint records, which an older checkpoint lacks.
    if steps == checkpoint.step && checkpoint.last_step.is_none() {
        bail!(
            "{}: this checkpoint (of an older hydrorattle-host) does not record its step's solve, which a run ending at t = {at} writes: resume to a later time, or run scene.toml again",
            dir.join(CHECKPOINT).display()
        );
    }
    let name = dir
        .file_name()
        .map_or_else(|| "run".to_string(), |s| s.to_string_lossy().into_owned());
    let start = Start {
        scene_path: Some(scene_path),
        checkpoint: Some(checkpoint),
        locked: false,
    };
    run_from(&scene, &name, Some(dir), opts, start).context("resuming")
}

fn snapshot<T: Real>(ps: &[T::V3], radius: &[T], time: T) -> Snapshot {
    Snapshot {
        time: time.to_f64(),
        positions: ps.iter().map(|&v| T::v3_to_f64(v)).collect(),
        radii: radius.iter().map(|r| r.to_f64()).collect(),
        wall: None,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Method, Solver};
    use crate::sizing::Plan;
    use hydrorattle::Layout;

    #[test]
    fn the_storage_checked_is_the_storage_the_kernel_asks_for() {
        let mut scene = Scene::figure1().unwrap().remove(0).1;
        for &method in Method::ALL {
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

    #[test]
    fn the_storage_checked_counts_the_thermal_noise() {
        use crate::scene::{Drift, Sqrt, Thermal};
        let mut scene = Scene::figure1().unwrap().remove(0).1;
        scene.contact = None;
        for method in [Method::Overdamped, Method::Springs] {
            for sqrt in [Sqrt::Auto, Sqrt::Cholesky, Sqrt::Lanczos] {
                for drift in [Drift::Midpoint, Drift::Uncorrected] {
                    scene.integrator.method = method;
                    scene.brownian = Some(Thermal {
                        temperature: 1.0,
                        seed: 1,
                        drift,
                        sqrt,
                    });
                    let (n, b) = (scene.particles.len(), scene.bonds.len());
                    let want = Layout::for_params(&params::<f64>(&scene), n, b);
                    let plain = Layout::for_params(
                        &params::<f64>(&Scene {
                            brownian: None,
                            ..scene.clone()
                        }),
                        n,
                        b,
                    );
                    assert_ne!(
                        want, plain,
                        "{method:?} {sqrt:?} {drift:?}: noise needs storage"
                    );
                    assert_eq!(Plan::of(&scene).layout(n, b), Some(want));
                }
            }
        }
    }
}
