//! Scene files and runs through the CLI's library code: the same parser, the same run,
//! the same files.

use std::path::PathBuf;

use hydrorattle_host::output::read_xyz_file;
use hydrorattle_host::scene::{Scene, SceneError};
use hydrorattle_host::sizing::{DEFAULT_LIMIT, DEFAULT_OUTPUT_LIMIT, Limits};
use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array3};
use pyo3::exceptions::{PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::scene_error;

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

/// Runs a scene file into `out` as `host-demo run` does (its data files; the CLI also
/// draws pictures after the run), with the GIL released;
/// returns `summary.json`'s text.
#[pyfunction]
#[pyo3(signature = (path, out, checkpoint_every=None, max_storage=None))]
pub fn run_scene(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    checkpoint_every: Option<f64>,
    max_storage: Option<usize>,
) -> PyResult<String> {
    let limits = Limits {
        storage: max_storage.unwrap_or(DEFAULT_LIMIT),
        output: DEFAULT_OUTPUT_LIMIT,
    };
    let r = py
        .detach(|| {
            hydrorattle_host::sim::run_scene_file(&path, &out, limits, checkpoint_every, false, 0)
        })
        .map_err(|e| host_error(py, e))?;
    if let Some(f) = &r.summary.failure {
        return Err(PyRuntimeError::new_err(format!(
            "the run stopped early: {f}"
        )));
    }
    serde_json::to_string(&r.summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))
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
