//! `step(n)`: the steps of a shared system, one lock per step ([`Shared`]), with the
//! GIL released unless a force callable needs it; Ctrl-C looked for every
//! [`SIGNAL_EVERY`]; a Python callback every `every` steps, run with the GIL held and
//! the lock released (it may read the system).

use std::time::{Duration, Instant};

use hydrorattle::{Real, StepError};
use hydrorattle_host::each_engine;
use hydrorattle_host::sim::AnyEngine;
use hydrorattle_host::sim::retry::Retries;
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::{step_error, with_attrs};
use crate::input::rows;
use crate::shared::Shared;
use crate::system::{Report, rows_f64};

/// How often a long `step(n)` looks for Ctrl-C.
const SIGNAL_EVERY: Duration = Duration::from_millis(20);

/// A callback and how many steps apart it runs.
pub struct Every {
    /// Called with no argument (the Python layer binds the system).
    pub callback: Py<PyAny>,
    /// Steps between two calls (>= 1).
    pub every: usize,
}

/// `n` steps of the shared system; the first failure ends them (the state as after
/// the last good step, `completed` on the exception).
pub fn steps(
    py: Python<'_>,
    shared: &Shared<AnyEngine>,
    n: usize,
    force: Option<&Bound<'_, PyAny>>,
    every: Option<Every>,
) -> PyResult<Report> {
    let _stepping = shared.begin()?;
    match force {
        None => py.detach(|| free_steps(shared, n, every.as_ref())),
        Some(f) => held_steps(py, shared, n, f, every.as_ref()),
    }
}

/// Runs the callback after step `done` when it is due.
fn call_back(py: Python<'_>, every: Option<&Every>, done: usize) -> PyResult<()> {
    match every {
        Some(c) if done.is_multiple_of(c.every) => c
            .callback
            .call0(py)
            .map(|_| ())
            .map_err(|e| completed(py, e, done)),
        _ => Ok(()),
    }
}

/// The steps with the GIL released (taken back for the callback, a failure and Ctrl-C).
fn free_steps(shared: &Shared<AnyEngine>, n: usize, every: Option<&Every>) -> PyResult<Report> {
    let mut last = empty(0);
    let mut checked = Instant::now();
    let mut start = None;
    for done in 1..=n {
        shared.give_way();
        let r: Result<Report, StepError> = {
            let mut g = shared.step_lock();
            each_engine!(&mut *g, e, T => {
                let from = *start.get_or_insert(e.retries);
                e.step().map(|r| Report::of::<T>(&r, done, since(e.retries, from)))
            })
        };
        last = r.map_err(|k| Python::attach(|py| completed(py, step_error(py, k), done - 1)))?;
        if every.is_some_and(|c| done.is_multiple_of(c.every)) {
            Python::attach(|py| call_back(py, every, done))?;
        }
        if done < n && checked.elapsed() >= SIGNAL_EVERY {
            Python::attach(|py| py.check_signals().map_err(|e| completed(py, e, done)))?;
            checked = Instant::now();
        }
    }
    Ok(last)
}

/// The steps with a force callable: the GIL held throughout.
fn held_steps(
    py: Python<'_>,
    shared: &Shared<AnyEngine>,
    n: usize,
    f: &Bound<'_, PyAny>,
    every: Option<&Every>,
) -> PyResult<Report> {
    let mut last = empty(0);
    let mut start = None;
    for done in 1..=n {
        if shared.readers_waiting() {
            py.detach(|| shared.give_way());
        }
        let mut g = shared.step_lock();
        let r = each_engine!(&mut *g, e, T => {
            let from = *start.get_or_insert(e.retries);
            let mut failed: Option<PyErr> = None;
            let mut extra = |pos: &[<T as Real>::V3], _: &[T], out: &mut [<T as Real>::V3]| {
                if failed.is_some() {
                    return;
                }
                if let Err(err) = call_force::<T>(py, f, pos, out) {
                    // A NaN force makes the kernel refuse the step, leaving the state
                    // as it was; the Python error is raised instead.
                    out.iter_mut().for_each(|v| *v = T::v3_from([f64::NAN; 3]));
                    failed = Some(err);
                }
            };
            let r = e.step_with(&mut extra);
            match failed {
                Some(err) => Err(err),
                None => r
                    .map(|r| Report::of::<T>(&r, done, since(e.retries, from)))
                    .map_err(|k| step_error(py, k)),
            }
        });
        drop(g);
        last = r.map_err(|e| completed(py, e, done - 1))?;
        call_back(py, every, done)?;
        if done < n {
            py.check_signals().map_err(|e| completed(py, e, done))?;
        }
    }
    Ok(last)
}

/// `err` with `completed`: the steps of this call that succeeded before it.
pub fn completed(py: Python<'_>, err: PyErr, done: usize) -> PyErr {
    let n = done.into_pyobject(py).map(|x| x.into_any().unbind());
    match n {
        Ok(n) => with_attrs(py, err, &[("completed", n)]),
        Err(_) => err,
    }
}

/// A report for a call that made no step.
pub fn empty(steps: usize) -> Report {
    Report {
        iterations: 0,
        velocity_iterations: 0,
        residual: 0.0,
        max_tension: 0.0,
        contacts: 0,
        wall_contacts: 0,
        contact_rounds: 0,
        noise_iterations: 0,
        steps,
        retried_steps: 0,
        retry_substeps: 0,
    }
}

/// The retries counted from `from` to `now` (the engine's totals at a call's start and
/// after its latest step).
fn since(now: Retries, from: Retries) -> Retries {
    Retries {
        steps: now.steps - from.steps,
        substeps: now.substeps - from.substeps,
    }
}

/// Calls `f(positions)` and adds its `(N, 3)` result into `out`.
fn call_force<T: Real>(
    py: Python<'_>,
    f: &Bound<'_, PyAny>,
    pos: &[T::V3],
    out: &mut [T::V3],
) -> PyResult<()> {
    let ret = f.call1((rows_f64::<T>(py, pos),))?;
    // A C-contiguous float64 array is read as it is; anything else goes through NumPy.
    let arr: PyReadonlyArray2<'_, f64> = match ret.extract::<PyReadonlyArray2<'_, f64>>() {
        Ok(a) if a.is_c_contiguous() => a,
        _ => py
            .import("numpy")?
            .call_method1("ascontiguousarray", (ret, "float64"))?
            .extract()
            .map_err(|_| {
                PyValueError::new_err(format!(
                    "the force callable must return shape ({}, 3)",
                    pos.len()
                ))
            })?,
    };
    let forces = rows(&arr, "the force callable's result")?;
    if forces.len() != out.len() {
        return Err(PyValueError::new_err(format!(
            "the force callable returned {} rows for {} particles",
            forces.len(),
            out.len()
        )));
    }
    for (o, &f) in out.iter_mut().zip(forces) {
        *o += T::v3_from(f);
    }
    Ok(())
}
