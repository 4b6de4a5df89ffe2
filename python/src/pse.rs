//! `mobility_dot` in a periodic box by the positively split Ewald fast path (the
//! kernel's `mobility::pse`, `O(N log N)`), and the choice between it and the Ewald sum
//! by the host library's rule (`hydrorattle_host::scene::pse_pays` and
//! `BoxMethod::resolve`, the rule a scene's `method = "auto"` follows).

use hydrorattle::mobility::pse::{Part, Pse, PseStorage};
use hydrorattle::{Hydro, Parallel, Periodic, Real, Serial, StepError};
use hydrorattle_host::scene::{BoxMethod, DEFAULT_BOX_TOLERANCE, pse_pays};
use hydrorattle_parallel::Threads;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::alloc;
use crate::errors::value_error;

/// The box method asked for (`"auto"`, `"ewald"`, `"pse"`) and the tolerance (PSE's
/// relative error; default the scenes' [`DEFAULT_BOX_TOLERANCE`]).
pub fn method(method: &str, tolerance: Option<f64>) -> PyResult<(BoxMethod, f64)> {
    let m = match method {
        "auto" => BoxMethod::Auto,
        // The exact product of each geometry: the Ewald sum in a box.
        "ewald" | "dense" => BoxMethod::Ewald,
        "pse" => BoxMethod::Pse,
        other => {
            return Err(PyValueError::new_err(format!(
                "method must be \"auto\", \"dense\", \"fast\", \"ewald\" or \"pse\", not {other:?}"
            )));
        }
    };
    Ok((m, tolerance.unwrap_or(DEFAULT_BOX_TOLERANCE)))
}

/// Whether the product runs by PSE: in a box, `"pse"`, or `"auto"` where the product
/// needs translation only with the RPY level (what PSE gives) and PSE runs there and
/// costs less than the Ewald sum (the measured cost model, `pse_pays`). `"pse"` where PSE cannot serve is a `ValueError` saying why.
pub fn uses_pse(
    (m, tolerance): (BoxMethod, f64),
    cell: Option<[f64; 3]>,
    radii: &[f64],
    level: Hydro,
    rotation: bool,
) -> PyResult<bool> {
    let Some(size) = cell else {
        return match m {
            BoxMethod::Pse => Err(PyValueError::new_err(
                "method = \"pse\" needs a periodic box (box=...)",
            )),
            _ => Ok(false),
        };
    };
    let products = !rotation && level == Hydro::Rpy;
    if m == BoxMethod::Pse && !products {
        return Err(PyValueError::new_err(
            "method = \"pse\" gives the translational RPY product only: no rotation or torques, hydro = \"rpy\"",
        ));
    }
    let a_max = radii.iter().fold(0.0, |m: f64, &a| m.max(a));
    // The tolerance's range is checked whatever the method (as a scene's key is).
    let range =
        hydrorattle::mobility::pse::MIN_TOLERANCE..=hydrorattle::mobility::pse::MAX_TOLERANCE;
    if !range.contains(&tolerance) {
        return Err(PyValueError::new_err(format!(
            "tolerance must be between {:e} and {} (PSE's relative error), not {tolerance}",
            range.start(),
            range.end()
        )));
    }
    let fits = products && pse_pays(size, radii.len(), a_max, tolerance);
    Ok(m.resolve(fits) == BoxMethod::Pse)
}

/// `u = M f` in the box `size` by PSE to `tolerance` (viscosity `eta`), its pieces run
/// by `par` (the same bits on any number of threads); the storage sized and reserved
/// first ([`alloc`]), the product run with the GIL released.
#[allow(clippy::too_many_arguments)]
pub fn product<T: Real>(
    py: Python<'_>,
    size: [f64; 3],
    tolerance: f64,
    eta: f64,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    u: &mut [T::V3],
    par: Option<&Threads>,
) -> PyResult<()> {
    let fail = |e: StepError| value_error(py, e);
    let cell = Periodic::new(size.map(T::from_f64)).map_err(|e| fail(e.into()))?;
    let a_max = radius.iter().fold(T::ZERO, |m, &a| m.max(a));
    let pse = Pse::new(cell, a_max, tolerance).map_err(|e| fail(e.into()))?;
    let need = pse.storage(pos.len());
    let what = format!("mobility_dot of {} spheres by PSE", pos.len());
    alloc::Need::new(&what)
        .add::<[T; 2]>("grid", Some(need.complex))
        .add::<usize>("cell list", Some(need.index))
        .add::<T::V3>("vectors", Some(need.vectors))
        .check()?;
    let mut complex = alloc::filled(&what, "grid", need.complex, [T::ZERO; 2])?;
    let mut index = alloc::filled(&what, "cell list", need.index, 0usize)?;
    let mut vectors = alloc::filled(&what, "vectors", need.vectors, T::V3_ZERO)?;
    py.detach(|| {
        let store = PseStorage::new(&mut complex, &mut index, &mut vectors);
        let par: &dyn Parallel = match par {
            Some(t) => t,
            None => &Serial,
        };
        let mut store = store.with_parallel(par);
        pse.apply(Part::Both, T::from_f64(eta), pos, radius, f, u, &mut store)
    })
    .map_err(|e| fail(e.into()))
}
