//! Python exceptions: `StepError` and its subclasses mirror the kernel's
//! [`hydrorattle::StepError`], each carrying `stage`, `index` and `value`;
//! `SceneError` (a `ValueError`) carries `file`, `line` and `column`.

use hydrorattle::{BondError, LinalgError as KLinalg, ParticleError, StepError as KStep};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

pyo3::create_exception!(
    hydrorattle,
    StepError,
    PyRuntimeError,
    "A step failed; the system's state is exactly as it was before the call."
);
pyo3::create_exception!(
    hydrorattle,
    InvalidStateError,
    StepError,
    "The parameters, particles or bonds were refused at the start of the step."
);
pyo3::create_exception!(
    hydrorattle,
    ConvergenceError,
    StepError,
    "A constraint solve hit its iteration cap (`index`: iterations, `value`: residual)."
);
pyo3::create_exception!(
    hydrorattle,
    LinalgError,
    StepError,
    "A factorisation failed (`stage`, `index`: the scalar row)."
);
pyo3::create_exception!(
    hydrorattle,
    DegenerateError,
    StepError,
    "A bond turned too far in one step (`index`: the bond)."
);
pyo3::create_exception!(
    hydrorattle,
    NonFiniteError,
    StepError,
    "A force, velocity or position became NaN or infinite (`index`: the particle)."
);
pyo3::create_exception!(
    hydrorattle,
    OverlapError,
    StepError,
    "Two spheres overlap or nest after the step (`index`: the pair)."
);
pyo3::create_exception!(
    hydrorattle,
    UnstableError,
    StepError,
    "The explicit-drag step is beyond its stability limit (`value`: the limit)."
);
pyo3::create_exception!(
    hydrorattle,
    ContactsFullError,
    StepError,
    "More spheres touch at once than the contact capacity (`index`: the capacity)."
);
pyo3::create_exception!(
    hydrorattle,
    UnsupportedError,
    StepError,
    "The combination asked for is not implemented."
);
pyo3::create_exception!(
    hydrorattle,
    SceneError,
    PyValueError,
    "A scene file could not be read or was refused (`file`, `line`, `column`)."
);

/// Adds the exceptions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("StepError", py.get_type::<StepError>())?;
    m.add("InvalidStateError", py.get_type::<InvalidStateError>())?;
    m.add("ConvergenceError", py.get_type::<ConvergenceError>())?;
    m.add("LinalgError", py.get_type::<LinalgError>())?;
    m.add("DegenerateError", py.get_type::<DegenerateError>())?;
    m.add("NonFiniteError", py.get_type::<NonFiniteError>())?;
    m.add("OverlapError", py.get_type::<OverlapError>())?;
    m.add("UnstableError", py.get_type::<UnstableError>())?;
    m.add("ContactsFullError", py.get_type::<ContactsFullError>())?;
    m.add("UnsupportedError", py.get_type::<UnsupportedError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    Ok(())
}

/// Sets attributes on an exception instance.
fn with_attrs(py: Python<'_>, e: PyErr, attrs: &[(&str, Py<PyAny>)]) -> PyErr {
    let v = e.value(py);
    for (k, x) in attrs {
        // An attribute that cannot be set leaves the message, which says the same.
        let _ = v.setattr(*k, x);
    }
    e
}

/// The particle index or pair a particle error names.
fn particle_index(py: Python<'_>, e: ParticleError) -> Py<PyAny> {
    let one = |i: usize| i.into_pyobject(py).map(|x| x.into_any().unbind()).ok();
    let pair = |i: usize, j: usize| PyTuple::new(py, [i, j]).map(|t| t.into_any().unbind()).ok();
    match e {
        ParticleError::NonFinite { particle }
        | ParticleError::BadRadius { particle }
        | ParticleError::BadDensity { particle }
        | ParticleError::Massless { particle }
        | ParticleError::BelowWall { particle } => one(particle),
        ParticleError::Nested { i, j } | ParticleError::Overlap { i, j } => pair(i, j),
        ParticleError::Full => None,
    }
    .unwrap_or_else(|| py.None())
}

/// The bond index a bond error names.
fn bond_index(e: BondError) -> Option<usize> {
    match e {
        BondError::SelfBond { bond, .. }
        | BondError::OutOfRange { bond, .. }
        | BondError::Duplicate { bond, .. }
        | BondError::BadLength { bond }
        | BondError::Violated { bond, .. }
        | BondError::Overstretched { bond, .. } => Some(bond),
        BondError::BadTree { particle } => Some(particle),
        BondError::Full => None,
    }
}

/// A kernel step error as the matching Python exception, with `kind`, `stage`,
/// `index` and `value` set (None where the error has none).
pub fn step_error(py: Python<'_>, e: KStep) -> PyErr {
    let msg = e.to_string();
    let none = || py.None();
    let int = |i: usize| {
        i.into_pyobject(py)
            .map_or_else(|_| py.None(), |x| x.into_any().unbind())
    };
    let float = |x: f64| {
        x.into_pyobject(py)
            .map_or_else(|_| py.None(), |x| x.into_any().unbind())
    };
    let text = |s: String| {
        s.into_pyobject(py)
            .map_or_else(|_| py.None(), |x| x.into_any().unbind())
    };
    let (err, kind, stage, index, value) = match e {
        KStep::BadTimeStep => (
            InvalidStateError::new_err(msg),
            "BadTimeStep",
            none(),
            none(),
            none(),
        ),
        KStep::BadParameter(_) => (
            InvalidStateError::new_err(msg),
            "BadParameter",
            none(),
            none(),
            none(),
        ),
        KStep::Particle(p) => (
            InvalidStateError::new_err(msg),
            "Particle",
            none(),
            particle_index(py, p),
            none(),
        ),
        KStep::Bond(b) => {
            let value = match b {
                BondError::Violated { residual, .. } => float(residual),
                BondError::Overstretched { ratio, .. } => float(ratio),
                _ => none(),
            };
            (
                InvalidStateError::new_err(msg),
                "Bond",
                none(),
                bond_index(b).map_or_else(none, int),
                value,
            )
        }
        KStep::Linalg { stage, error } => {
            let row = match error {
                KLinalg::NotPositiveDefinite { row } | KLinalg::Singular { row } => row,
            };
            (
                LinalgError::new_err(msg),
                "Linalg",
                text(format!("{stage:?}")),
                int(row),
                none(),
            )
        }
        KStep::NoConvergence {
            stage,
            iterations,
            residual,
        } => (
            ConvergenceError::new_err(msg),
            "NoConvergence",
            text(format!("{stage:?}")),
            int(iterations as usize),
            float(residual),
        ),
        KStep::Degenerate { bond } => (
            DegenerateError::new_err(msg),
            "Degenerate",
            none(),
            int(bond),
            none(),
        ),
        KStep::NonFinite { particle } => (
            NonFiniteError::new_err(msg),
            "NonFinite",
            none(),
            int(particle),
            none(),
        ),
        KStep::Overlap { i, j } => (
            OverlapError::new_err(msg),
            "Overlap",
            none(),
            particle_index(py, ParticleError::Overlap { i, j }),
            none(),
        ),
        KStep::Storage { .. } => (
            InvalidStateError::new_err(msg),
            "Storage",
            none(),
            none(),
            none(),
        ),
        KStep::StateLength => (
            InvalidStateError::new_err(msg),
            "StateLength",
            none(),
            none(),
            none(),
        ),
        KStep::Unstable { dt: _, limit } => (
            UnstableError::new_err(msg),
            "Unstable",
            none(),
            none(),
            float(limit),
        ),
        KStep::ContactsFull { capacity } => (
            ContactsFullError::new_err(msg),
            "ContactsFull",
            none(),
            int(capacity),
            none(),
        ),
        KStep::Unsupported(_) => (
            UnsupportedError::new_err(msg),
            "Unsupported",
            none(),
            none(),
            none(),
        ),
    };
    with_attrs(
        py,
        err,
        &[
            ("kind", text(kind.to_string())),
            ("stage", stage),
            ("index", index),
            ("value", value),
        ],
    )
}

/// A refused particle as a `ValueError` naming it (`index` set).
pub fn particle_error(py: Python<'_>, e: ParticleError) -> PyErr {
    let index = particle_index(py, e);
    with_attrs(
        py,
        PyValueError::new_err(e.to_string()),
        &[("index", index)],
    )
}

/// A refused bond as a `ValueError` naming it.
pub fn bond_error(e: BondError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A scene error as `SceneError` with `file`, `line` and `column`.
pub fn scene_error(py: Python<'_>, e: &hydrorattle_host::scene::SceneError) -> PyErr {
    let text = |s: &str| {
        s.into_pyobject(py)
            .map_or_else(|_| py.None(), |x| x.into_any().unbind())
    };
    let int = |i: Option<usize>| {
        i.and_then(|i| i.into_pyobject(py).ok())
            .map_or_else(|| py.None(), |x| x.into_any().unbind())
    };
    with_attrs(
        py,
        SceneError::new_err(e.to_string()),
        &[
            ("file", text(&e.origin)),
            ("line", int(e.line())),
            ("column", int(e.location.map(|l| l.1))),
        ],
    )
}
