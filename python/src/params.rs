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

/// What a system's keyword arguments set beside the kernel's parameters.
pub struct Extras {
    /// The noise generator's seed.
    pub seed: u64,
    /// Threads for the mobility's bands (0: every core).
    pub threads: usize,
}

/// A keyword argument's value as `X`, or a `TypeError` naming the parameter and the
/// type it got.
fn get<'py, X: for<'a> pyo3::FromPyObject<'a, 'py>>(
    k: &str,
    x: &Bound<'py, PyAny>,
    want: &str,
) -> PyResult<X> {
    if x.is_instance_of::<pyo3::types::PyComplex>() {
        return Err(PyTypeError::new_err(format!(
            "{k} must be {want}, not a complex number"
        )));
    }
    x.extract::<X>()
        .map_err(|_| PyTypeError::new_err(format!("{k} must be {want}, not {}", type_name(x))))
}

/// A flag: `True`/`False` (NumPy's too), or the integers 1 and 0 meaning them.
fn flag(k: &str, x: &Bound<'_, PyAny>) -> PyResult<bool> {
    if let Ok(b) = x.extract::<bool>() {
        return Ok(b);
    }
    if x.is_instance_of::<pyo3::types::PyInt>() {
        match x.extract::<i64>() {
            Ok(0) => return Ok(false),
            Ok(1) => return Ok(true),
            _ => {}
        }
    }
    let shown = x.repr().map_or_else(|_| type_name(x), |r| r.to_string());
    Err(PyTypeError::new_err(format!(
        "{k} must be True or False, not {shown}"
    )))
}

/// The type name of `x`, for messages.
fn type_name(x: &Bound<'_, PyAny>) -> String {
    x.get_type()
        .name()
        .map_or_else(|_| "?".into(), |n| n.to_string())
}

/// An integer (Python's or NumPy's, not a bool) that fits `X`: a `TypeError` naming the
/// parameter for another type, a `ValueError` for a value out of range (a negative
/// seed, say).
fn count<X: TryFrom<i128>>(k: &str, x: &Bound<'_, PyAny>) -> PyResult<X> {
    let not_int = || PyTypeError::new_err(format!("{k} must be an integer, not {}", type_name(x)));
    if x.is_instance_of::<pyo3::types::PyBool>() {
        return Err(not_int());
    }
    let v: i128 = x.extract().map_err(|_| not_int())?;
    X::try_from(v).map_err(|_| {
        let max = std::any::type_name::<X>();
        PyValueError::new_err(format!(
            "{k} must be an integer in the range of {max} (>= 0), not {v}"
        ))
    })
}

/// Largest contact capacity: a scene's `[contact] capacity` bound.
const MAX_CAPACITY: usize = 1 << 32;

/// A hard-contact capacity, from 1 to [`MAX_CAPACITY`] as in a scene.
fn capacity(x: &Bound<'_, PyAny>) -> PyResult<usize> {
    let c: usize = count("contacts", x)?;
    if !(1..=MAX_CAPACITY).contains(&c) {
        return Err(PyValueError::new_err(format!(
            "contacts (the capacity) must be a whole number from 1 to 2^32 (contacts at once), not {c}"
        )));
    }
    Ok(c)
}

/// `near_field=`: `False` or `None` (off), `True` (the kernel's defaults), or a dict of
/// `cutoff`, `wall_cutoff`, `min_gap` (radii; the others default). Its range checks
/// are the kernel's, when the system is built.
fn near_field<T: Real>(
    x: &Bound<'_, PyAny>,
) -> PyResult<Option<hydrorattle::stokesian::NearField<T>>> {
    let mut near = hydrorattle::stokesian::NearField::<T>::default();
    if x.is_none() {
        return Ok(None);
    }
    let Ok(d) = x.cast::<PyDict>() else {
        return Ok(flag("near_field", x)?.then_some(near));
    };
    for (k, v) in d.iter() {
        let k: String = k.extract()?;
        let v = T::from_f64(get(&k, &v, "a real number")?);
        match k.as_str() {
            "cutoff" => near.cutoff = v,
            "wall_cutoff" => near.wall_cutoff = v,
            "min_gap" => near.min_gap = v,
            other => {
                return Err(PyTypeError::new_err(format!(
                    "near_field got an unexpected key {other:?} (cutoff, wall_cutoff, min_gap)"
                )));
            }
        }
    }
    Ok(Some(near))
}

/// Kernel parameters in precision `T` from keyword arguments with the kernel's names
/// and defaults ([`Params::new`]); the seed and thread count come back beside them.
/// A value of the wrong type is a `TypeError`, a value out of range a `ValueError`,
/// each naming the parameter (the kernel's own checks run when the system is built).
pub fn params_from<T: Real>(kw: Option<&Bound<'_, PyDict>>) -> PyResult<(Params<T>, Extras)> {
    let dt: f64 = match kw.map(|d| d.get_item("dt")).transpose()?.flatten() {
        Some(x) => get("dt", &x, "a real number")?,
        None => return Err(PyTypeError::new_err("System needs the time step dt")),
    };
    let mut p = Params::<T>::new(T::from_f64(dt));
    let mut extras = Extras {
        seed: 1,
        threads: 0,
    };
    let Some(d) = kw else {
        return Ok((p, extras));
    };
    let mut temperature = None;
    let mut drift = Drift::default();
    for (k, x) in d.iter() {
        let k: String = k.extract()?;
        let k = k.as_str();
        let real =
            |x: &Bound<'_, PyAny>| -> PyResult<T> { Ok(T::from_f64(get(k, x, "a real number")?)) };
        let v3 = |x: &Bound<'_, PyAny>| -> PyResult<T::V3> {
            Ok(T::v3_from(get::<[f64; 3]>(k, x, "three real numbers")?))
        };
        let name = |x: &Bound<'_, PyAny>| -> PyResult<String> { get(k, x, "a string") };
        match k {
            "dt" => {}
            "method" => p.method = pick::<Method>("method", &name(&x)?)?,
            "viscosity" => p.viscosity = real(&x)?,
            "fluid_density" => p.fluid_density = real(&x)?,
            "gravity" => p.gravity = v3(&x)?,
            "flow" | "flow_velocity" => p.flow_velocity = v3(&x)?,
            "vorticity" => p.vorticity = v3(&x)?,
            "hydro" => p.hydro = crate::input::hydro(&name(&x)?)?,
            "rotation" => p.rotation = flag(k, &x)?,
            "matrix_free" => p.matrix_free = flag(k, &x)?,
            "compact_products" => p.compact_products = flag(k, &x)?,
            "solver" => p.solver.kind = pick::<SolverKind>("solver", &name(&x)?)?,
            "tolerance" => p.solver.tolerance = real(&x)?,
            "max_iterations" => p.solver.max_iterations = count(k, &x)?,
            "allow_overlap" => p.allow_overlap = flag(k, &x)?,
            "spring_stiffness" => p.spring_stiffness = real(&x)?,
            "fene" => p.fene = (!x.is_none()).then(|| real(&x)).transpose()?,
            "stability_guard" => p.stability_guard = flag(k, &x)?,
            "resolve_tensions" => p.resolve_tensions = flag(k, &x)?,
            "contacts" => {
                p.contacts = (!x.is_none())
                    .then(|| capacity(&x))
                    .transpose()?
                    .map(Contacts::new);
            }
            "wall" => p.wall = (!x.is_none()).then(|| real(&x)).transpose()?.map(Wall::new),
            "box" => {
                if !x.is_none() {
                    let edges = get::<[f64; 3]>(k, &x, "three real numbers")?;
                    p.periodic = Some(crate::input::cell::<T>(edges)?);
                }
            }
            "temperature" => temperature = (!x.is_none()).then(|| real(&x)).transpose()?,
            "drift" => drift = pick::<Drift>("drift", &name(&x)?)?,
            "seed" => extras.seed = count(k, &x)?,
            "threads" => extras.threads = count(k, &x)?,
            "noise_sqrt" => p.noise_sqrt = pick::<NoiseSqrt>("noise_sqrt", &name(&x)?)?,
            "lanczos_tolerance" => p.lanczos.tolerance = real(&x)?,
            "lanczos_max_iterations" => p.lanczos.max_iterations = count(k, &x)?,
            "near_field" => p.near = near_field::<T>(&x)?,
            other => {
                return Err(PyTypeError::new_err(format!(
                    "System got an unexpected parameter {other:?}"
                )));
            }
        }
    }
    p.brownian = temperature.map(|t| Brownian {
        temperature: t,
        drift,
    });
    Ok((p, extras))
}
