//! Kernel parameters from keyword arguments, with the kernel's names and defaults.

use hydrorattle::{Brownian, Contacts, Drift, Method, NoiseSqrt, Params, Real, SolverKind, Wall};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A named choice, or a `ValueError` listing the names.
fn pick<X: Copy>(what: &str, name: &str, choices: &[(&str, X)]) -> PyResult<X> {
    choices
        .iter()
        .find(|(n, _)| *n == name)
        .map(|&(_, x)| x)
        .ok_or_else(|| {
            let names: Vec<&str> = choices.iter().map(|(n, _)| *n).collect();
            PyValueError::new_err(format!("{what} must be one of {names:?}, not {name:?}"))
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
            "method" => {
                p.method = pick(
                    "method",
                    &x.extract::<String>()?,
                    &[
                        ("overdamped", Method::Overdamped),
                        ("overdamped2", Method::Overdamped2),
                        ("rattle", Method::Rattle),
                        ("rattle-stable", Method::RattleStable),
                        ("springs", Method::Springs),
                    ],
                )?
            }
            "viscosity" => p.viscosity = T::from_f64(x.extract()?),
            "fluid_density" => p.fluid_density = T::from_f64(x.extract()?),
            "gravity" => p.gravity = v3(x)?,
            "flow" | "flow_velocity" => p.flow_velocity = v3(x)?,
            "vorticity" => p.vorticity = v3(x)?,
            "hydro" => p.hydro = crate::input::hydro(&x.extract::<String>()?)?,
            "rotation" => p.rotation = x.extract()?,
            "matrix_free" => p.matrix_free = x.extract()?,
            "solver" => {
                p.solver.kind = pick(
                    "solver",
                    &x.extract::<String>()?,
                    &[
                        ("auto", SolverKind::Auto),
                        ("sweep", SolverKind::Sweep),
                        ("newton", SolverKind::Newton),
                        ("krylov", SolverKind::Krylov),
                    ],
                )?
            }
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
            "drift" => {
                drift = pick(
                    "drift",
                    &x.extract::<String>()?,
                    &[
                        ("midpoint", Drift::Midpoint),
                        ("uncorrected", Drift::Uncorrected),
                    ],
                )?
            }
            "seed" => seed = x.extract()?,
            "noise_sqrt" => {
                p.noise_sqrt = pick(
                    "noise_sqrt",
                    &x.extract::<String>()?,
                    &[
                        ("auto", NoiseSqrt::Auto),
                        ("cholesky", NoiseSqrt::Cholesky),
                        ("lanczos", NoiseSqrt::Lanczos),
                    ],
                )?
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
