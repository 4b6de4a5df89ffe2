//! Python exceptions: `StepError` and its subclasses mirror the kernel's
//! [`hydrorattle::StepError`], each carrying `stage`, `index` and `value`;
//! `SceneError` (a `ValueError`) carries `file`, `line` and `column`.

use hydrorattle::{BondError, ParticleError, StepError as KStep};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

pyo3::create_exception!(
    hydrorattle,
    StepError,
    PyRuntimeError,
    "A step failed. The failed step changed nothing: the state (and noise generator) is as after the last completed step; `step(n)` keeps the steps it completed before the failure, and `completed` says how many (0: the state is as before the call)."
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
    "A bond turned too far in one step, or constraints that cannot all hold (`index`: the bond, or the first of the dependent set)."
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
    SystemBusyError,
    PyRuntimeError,
    "The system is stepping: a second step(n) or a set_state from another thread while one runs, or a read of the system from inside its own step (a force callable reads the positions it is passed). Reads from other threads wait for the end of the current step instead."
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
    m.add("SystemBusyError", py.get_type::<SystemBusyError>())?;
    Ok(())
}

/// Sets attributes on an exception instance.
pub fn with_attrs(py: Python<'_>, e: PyErr, attrs: &[(&str, Py<PyAny>)]) -> PyErr {
    let v = e.value(py);
    for (k, x) in attrs {
        // An attribute that cannot be set leaves the message, which says the same.
        let _ = v.setattr(*k, x);
    }
    e
}

/// A Python index: the pair of an overlap or nesting, else the one index.
fn index_of(py: Python<'_>, pair: Option<(usize, usize)>, one: Option<usize>) -> Py<PyAny> {
    let obj = match (pair, one) {
        (Some((i, j)), _) => PyTuple::new(py, [i, j]).map(|t| t.into_any().unbind()).ok(),
        (None, Some(i)) => i.into_pyobject(py).map(|x| x.into_any().unbind()).ok(),
        (None, None) => None,
    };
    obj.unwrap_or_else(|| py.None())
}

/// A kernel step error as the matching Python exception, with the kernel's parts
/// ([`KStep::kind`], ...): `kind`, `stage` (the stage's name), `index` (the particle,
/// bond or row at fault, a pair as a tuple, or the iterations done / the contact
/// capacity) and `value` (the residual or ratio, or for `UnstableError` the limit);
/// None where the error has none.
pub fn step_error(py: Python<'_>, e: KStep) -> PyErr {
    let msg = e.to_string();
    let err = match e {
        KStep::Linalg { .. } => LinalgError::new_err(msg),
        KStep::NoConvergence { .. } => ConvergenceError::new_err(msg),
        KStep::Degenerate { .. } | KStep::Infeasible { .. } => DegenerateError::new_err(msg),
        KStep::NonFinite { .. } | KStep::NonFiniteForce { .. } => NonFiniteError::new_err(msg),
        KStep::Overlap { .. } => OverlapError::new_err(msg),
        KStep::Unstable { .. } => UnstableError::new_err(msg),
        KStep::ContactsFull { .. } => ContactsFullError::new_err(msg),
        KStep::Unsupported(_) => UnsupportedError::new_err(msg),
        KStep::BadTimeStep
        | KStep::BadParameter(_)
        | KStep::Particle(_)
        | KStep::Bond(_)
        | KStep::Storage { .. }
        | KStep::StateLength => InvalidStateError::new_err(msg),
    };
    let text = |s: &str| {
        s.into_pyobject(py)
            .map_or_else(|_| py.None(), |x| x.into_any().unbind())
    };
    let float = |x: Option<f64>| {
        x.and_then(|x| x.into_pyobject(py).ok())
            .map_or_else(|| py.None(), |x| x.into_any().unbind())
    };
    let value = match e {
        KStep::Unstable { .. } => e.limit(),
        _ => e.value(),
    };
    with_attrs(
        py,
        err,
        &[
            ("kind", text(e.kind())),
            (
                "stage",
                e.stage().map_or_else(|| py.None(), |s| text(s.name())),
            ),
            ("index", index_of(py, e.pair(), e.index().or(e.count()))),
            ("value", float(value)),
        ],
    )
}

/// A refused particle as a `ValueError` naming it (`index` set).
pub fn particle_error(py: Python<'_>, e: ParticleError) -> PyErr {
    let index = index_of(py, e.pair(), e.index());
    let kind = kind_of(py, KStep::Particle(e));
    with_attrs(
        py,
        PyValueError::new_err(e.to_string()),
        &[("index", index), ("kind", kind)],
    )
}

/// A `ValueError` with `message` about particle `index`, of the kernel's `kind` for
/// `like` (a refusal the package words itself, where the kernel's words would mislead).
pub fn particle_message(
    py: Python<'_>,
    message: String,
    index: usize,
    like: ParticleError,
) -> PyErr {
    let kind = kind_of(py, KStep::Particle(like));
    let index = index_of(py, None, Some(index));
    with_attrs(
        py,
        PyValueError::new_err(message),
        &[("index", index), ("kind", kind)],
    )
}

/// The kernel's kind of `e` as a Python string.
fn kind_of(py: Python<'_>, e: KStep) -> Py<PyAny> {
    e.kind()
        .into_pyobject(py)
        .map_or_else(|_| py.None(), |x| x.into_any().unbind())
}

/// A kernel error met outside a step (the mobility alone, a system's construction) as
/// a `ValueError` with the kernel's message and `kind` (and `index` for a particle).
pub fn value_error(py: Python<'_>, e: KStep) -> PyErr {
    match e {
        KStep::Particle(p) => return particle_error(py, p),
        KStep::Bond(b) => return bond_error(py, b),
        _ => {}
    }
    let kind = kind_of(py, e);
    with_attrs(py, PyValueError::new_err(e.to_string()), &[("kind", kind)])
}

/// A refused bond as a `ValueError` naming it (`index`: the bond, or the particle of a
/// refused tree).
pub fn bond_error(py: Python<'_>, e: BondError) -> PyErr {
    let kind = kind_of(py, KStep::Bond(e));
    let index = index_of(py, None, e.index());
    with_attrs(
        py,
        PyValueError::new_err(e.to_string()),
        &[("index", index), ("kind", kind)],
    )
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
