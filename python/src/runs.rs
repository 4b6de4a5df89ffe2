//! Scene files and runs through the CLI's library code: the same parser, the same run,
//! the same files.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use hydrorattle_host::output::read_xyz_file;
use hydrorattle_host::scene::{Scene, SceneError};
use hydrorattle_host::sim::{Interrupted, RunOptions, RunResult, Stop};
use hydrorattle_host::sizing::{DEFAULT_LIMIT, DEFAULT_OUTPUT_LIMIT, Limits};
use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array3};
use pyo3::exceptions::{PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{scene_error, with_attrs};

/// An error of the host library as a Python exception: `SceneError` for a scene,
/// `RuntimeError` otherwise (with the whole chain of causes).
fn host_error(py: Python<'_>, e: anyhow::Error) -> PyErr {
    match e.downcast_ref::<SceneError>() {
        Some(s) => scene_error(py, s),
        None => PyRuntimeError::new_err(format!("{e:#}")),
    }
}

/// The resolved scene of a file as JSON text (`hydrorattle.load_scene` parses it).
#[pyfunction]
pub fn load_scene_json(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    let scene = Scene::from_path(&path).map_err(|e| scene_error(py, &e))?;
    serde_json::to_string(&scene).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// SIGINT's number: what a stop asked for by Ctrl-C records.
const SIGINT: usize = 2;

/// How often the calling thread looks for Ctrl-C while a run goes on.
const SIGNAL_EVERY: Duration = Duration::from_millis(20);

/// Runs `work` (a run given its [`Stop`]) on a thread of its own while this thread,
/// the GIL released between looks, checks for Ctrl-C (Python's signal handlers) every
/// [`SIGNAL_EVERY`]. A pending signal sets the run's stop flag: the run checkpoints
/// at the step it reached and ends ([`Interrupted`]); its result comes back with the
/// signal's Python error (`KeyboardInterrupt`), which the caller raises.
fn watched<R: Send>(py: Python<'_>, work: impl FnOnce(Stop) -> R + Send) -> (R, Option<PyErr>) {
    // `Stop` reads a `'static` flag: one word per call, kept for the process.
    let flag: &'static AtomicUsize = Box::leak(Box::new(AtomicUsize::new(0)));
    let mut signal = None;
    let result = std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel();
        let worker = s.spawn(move || {
            let r = work(Stop::on(flag));
            // The receiver outlives the worker (it is joined below).
            let _ = tx.send(());
            r
        });
        let mut rx = rx;
        loop {
            // The receiver goes into the GIL-free wait and back (it is not `Sync`).
            let (waited, back) = py.detach(move || (rx.recv_timeout(SIGNAL_EVERY), rx));
            rx = back;
            if !matches!(waited, Err(mpsc::RecvTimeoutError::Timeout)) {
                break;
            }
            if signal.is_none()
                && let Err(e) = py.check_signals()
            {
                flag.store(SIGINT, Ordering::Relaxed);
                signal = Some(e);
            }
        }
        py.detach(move || worker.join())
    });
    match result {
        Ok(r) => (r, signal),
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

/// A run's outcome as Python sees it: `summary.json`'s text; the signal's error (with
/// `checkpoint`, `step` and `time` of the stop) when Ctrl-C stopped it; `SceneError`
/// or `RuntimeError` for a failure.
fn outcome(
    py: Python<'_>,
    (r, signal): (anyhow::Result<RunResult>, Option<PyErr>),
) -> PyResult<String> {
    if let Some(e) = signal {
        let stop = r
            .as_ref()
            .err()
            .and_then(|e| e.downcast_ref::<Interrupted>());
        let attrs = match stop {
            Some(i) => vec![
                (
                    "checkpoint",
                    i.checkpoint.clone().into_pyobject(py)?.into_any().unbind(),
                ),
                ("step", i.step.into_pyobject(py)?.into_any().unbind()),
                ("time", i.time.into_pyobject(py)?.into_any().unbind()),
            ],
            None => Vec::new(),
        };
        return Err(with_attrs(py, e, &attrs));
    }
    let r = r.map_err(|e| host_error(py, e))?;
    if let Some(f) = &r.summary.failure {
        return Err(PyRuntimeError::new_err(format!(
            "the run stopped early: {f}"
        )));
    }
    serde_json::to_string(&r.summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// Runs a scene file into `out` as `host-demo run` does (its data files; the CLI also
/// draws pictures after the run), on a thread of its own, Ctrl-C stopping it between
/// two steps with a checkpoint ([`watched`]); returns `summary.json`'s text.
#[pyfunction]
#[pyo3(signature = (path, out, checkpoint_every=None, max_storage=None))]
pub fn run_scene(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    checkpoint_every: Option<f64>,
    max_storage: Option<usize>,
) -> PyResult<String> {
    let limits = limits(max_storage);
    let done = watched(py, |stop| {
        let opts = RunOptions {
            stop,
            ..RunOptions::files(limits, checkpoint_every, false)
        };
        hydrorattle_host::sim::run_scene_file_with(&path, &out, limits, opts)
    });
    outcome(py, done)
}

/// Continues the run in `out` from its checkpoint to time `until` (default: the end
/// its `scene.toml` names) as `host-demo resume` does; Ctrl-C as in [`run_scene`].
#[pyfunction]
#[pyo3(signature = (out, until=None, checkpoint_every=None, max_storage=None))]
pub fn resume_run(
    py: Python<'_>,
    out: PathBuf,
    until: Option<f64>,
    checkpoint_every: Option<f64>,
    max_storage: Option<usize>,
) -> PyResult<String> {
    let limits = limits(max_storage);
    let until = match until {
        Some(t) => t,
        None => {
            let scene = out.join(hydrorattle_host::sim::SCENE_TOML);
            let unlimited = Limits {
                output: u64::MAX,
                ..limits
            };
            Scene::from_path_limited(&scene, unlimited)
                .map_err(|e| scene_error(py, &e))?
                .integrator
                .duration
        }
    };
    let done = watched(py, |stop| {
        let opts = RunOptions {
            stop,
            ..RunOptions::files(limits, checkpoint_every, false)
        };
        hydrorattle_host::sim::resume(&out, until, limits, opts)
    });
    outcome(py, done)
}

/// The storage limit asked for (the CLI's default otherwise) and the CLI's output limit.
fn limits(max_storage: Option<usize>) -> Limits {
    Limits {
        storage: max_storage.unwrap_or(DEFAULT_LIMIT),
        output: DEFAULT_OUTPUT_LIMIT,
    }
}

/// The frames of `trajectory.xyz` in `dir`: time `(F,)`, positions and velocities
/// `(F, N, 3)`, radii and masses `(N,)` (of the first frame), species.
#[pyfunction]
pub fn read_trajectory<'py>(py: Python<'py>, dir: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let path = dir.join(hydrorattle_host::sim::TRAJECTORY_XYZ);
    let frames = py
        .detach(|| read_xyz_file(&path))
        .map_err(|e| PyOSError::new_err(format!("{e:#}")))?;
    let n = frames.first().map_or(0, |f| f.positions.len());
    if let Some(k) = frames.iter().position(|f| f.positions.len() != n) {
        return Err(PyRuntimeError::new_err(format!(
            "{}: frame {k} has {} particles, the first {n}",
            path.display(),
            frames[k].positions.len()
        )));
    }
    let stack = |get: fn(&hydrorattle_host::output::Frame) -> &Vec<[f64; 3]>| {
        let flat: Vec<f64> = frames
            .iter()
            .flat_map(|f| get(f).iter().flatten().copied())
            .collect();
        Array3::from_shape_vec((frames.len(), n, 3), flat).expect("n rows per frame")
    };
    let d = PyDict::new(py);
    d.set_item(
        "time",
        Array1::from_iter(frames.iter().map(|f| f.time)).into_pyarray(py),
    )?;
    d.set_item("positions", stack(|f| &f.positions).into_pyarray(py))?;
    d.set_item("velocities", stack(|f| &f.velocities).into_pyarray(py))?;
    let first = frames.first().cloned().unwrap_or_default();
    d.set_item("radii", Array1::from(first.radii).into_pyarray(py))?;
    d.set_item("masses", Array1::from(first.masses).into_pyarray(py))?;
    d.set_item("species", first.species)?;
    Ok(d)
}
