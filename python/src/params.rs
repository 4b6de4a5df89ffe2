//! Kernel parameters from keyword arguments, with the kernel's names and defaults.

use hydrorattle::{
    Brownian, Contacts, Drift, Method, Named, NoiseSqrt, Params, Real, SolverKind, Wall,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The kernel's value called `name` ([`Named::from_name`]), or a `ValueError` listing
/// the kernel's names for `what`.
pub fn pick<X: Named>(what: &str, name: &str) -> PyResult<X> {
    X::from_name(name).map_err(|e| {
        let names = e.expected.join("\", \"");
        PyValueError::new_err(format!("{what} must be one of \"{names}\", not {name:?}"))
    })
}

/// Kernel parameters in precision `T` from keyword arguments with the kernel's names
/// and defaults ([`Params::new`]); the noise seed comes back beside them.
pub fn params_from<T: Real>(kw: Option<&Bound<'_, PyDict>>) -> PyResult<(Params<T>, u64)> {
    let get = |k: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        match kw {
            Some(d) => d.get_item(k),
            None => Ok(None),
        }
    };
    let dt: f64 = get("dt")?
        .ok_or_else(|| PyTypeError::new_err("System needs the time step dt"))?
        .extract()?;
    let mut p = Params::<T>::new(T::from_f64(dt));
    let mut seed = 1;
    let v3 = |x: Bound<'_, PyAny>| -> PyResult<T::V3> { Ok(T::v3_from(x.extract::<[f64; 3]>()?)) };
    let Some(d) = kw else {
        return Ok((p, seed));
    };
    let mut temperature = None;
    let mut drift = Drift::default();
    for (k, x) in d.iter() {
        let k: String = k.extract()?;
        match k.as_str() {
            "dt" => {}
            "method" => p.method = pick::<Method>("method", &x.extract::<String>()?)?,
            "viscosity" => p.viscosity = T::from_f64(x.extract()?),
            "fluid_density" => p.fluid_density = T::from_f64(x.extract()?),
            "gravity" => p.gravity = v3(x)?,
            "flow" | "flow_velocity" => p.flow_velocity = v3(x)?,
            "vorticity" => p.vorticity = v3(x)?,
            "hydro" => p.hydro = crate::input::hydro(&x.extract::<String>()?)?,
            "rotation" => p.rotation = x.extract()?,
            "matrix_free" => p.matrix_free = x.extract()?,
            "solver" => p.solver.kind = pick::<SolverKind>("solver", &x.extract::<String>()?)?,
            "tolerance" => p.solver.tolerance = T::from_f64(x.extract()?),
            "max_iterations" => p.solver.max_iterations = x.extract()?,
            "allow_overlap" => p.allow_overlap = x.extract()?,
            "spring_stiffness" => p.spring_stiffness = T::from_f64(x.extract()?),
            "fene" => p.fene = x.extract::<Option<f64>>()?.map(T::from_f64),
            "stability_guard" => p.stability_guard = x.extract()?,
            "contacts" => {
                p.contacts = x.extract::<Option<usize>>()?.map(Contacts::new);
            }
            "wall" => {
                p.wall = x
                    .extract::<Option<f64>>()?
                    .map(|h| Wall::new(T::from_f64(h)))
            }
            "temperature" => temperature = x.extract::<Option<f64>>()?,
            "drift" => drift = pick::<Drift>("drift", &x.extract::<String>()?)?,
            "seed" => seed = x.extract()?,
            "noise_sqrt" => {
                p.noise_sqrt = pick::<NoiseSqrt>("noise_sqrt", &x.extract::<String>()?)?
            }
            "lanczos_tolerance" => p.lanczos.tolerance = T::from_f64(x.extract()?),
            "lanczos_max_iterations" => p.lanczos.max_iterations = x.extract()?,
            other => {
                return Err(PyTypeError::new_err(format!(
                    "System got an unexpected parameter {other:?}"
                )));
            }
        }
    }
    p.brownian = temperature.map(|t| Brownian {
        temperature: T::from_f64(t),
        drift,
    });
    Ok((p, seed))
}
