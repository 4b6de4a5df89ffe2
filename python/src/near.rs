//! `mobility(..., near_field=True)`: the dense Stokesian dynamics mobility, the inverse
//! of `M_far^-1 + R_near` ([`hydrorattle::stokesian`]), in free space, above a wall or
//! in a periodic box (Ewald sums by the kernel's rule, pairs at their minimum image).

use hydrorattle::Real;
use hydrorattle::mobility::periodic::Ewald;
use hydrorattle::stokesian::{Far, NearField, SdError, mobility_in, storage};
use numpy::ndarray::Array2;
use numpy::{Element, IntoPyArray, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::alloc;
use crate::errors::particle_error;
use crate::input::spheres;

/// The dense SD mobility in `T`: `(6N, 6N)` with rotation, else its `(3N, 3N)`
/// translational block (the mobility of torque-free spheres).
pub fn dense<'py, T: Real + Element>(
    py: Python<'py>,
    pos: &[[f64; 3]],
    radii: &[f64],
    eta: f64,
    rotation: bool,
    wall: Option<f64>,
    cell: Option<[f64; 3]>,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let n = pos.len();
    let what = format!("near-field mobility of {n} spheres");
    let (nb, nd) = storage(n);
    alloc::Need::new(&what)
        .add::<T::M3>("packed blocks", Some(nb))
        .add::<T>("resistance", Some(nd))
        .check()?;
    if let Some(c) = cell {
        crate::input::in_box::<T>(py, c, pos, radii)?;
    }
    let (p, r) = spheres::<T>(py, pos, radii, None)?;
    let ewald = match cell {
        Some(c) => {
            let a_max = r.iter().fold(T::ZERO, |m, &a| m.max(a));
            Some(
                Ewald::new(crate::input::cell::<T>(c)?, a_max)
                    .map_err(|e| PyValueError::new_err(format!("box: {e}")))?,
            )
        }
        None => None,
    };
    let mut packed = alloc::filled(&what, "packed blocks", nb, T::M3_ZERO)?;
    let mut out = alloc::filled(&what, "resistance", nd, T::ZERO)?;
    let eta = T::from_f64(eta);
    let far = match (&ewald, wall) {
        (Some(e), _) => Far::periodic(e),
        (None, Some(h)) => Far::above(T::from_f64(h)),
        (None, None) => Far::FREE,
    };
    let near = NearField::default();
    py.detach(|| mobility_in(eta, far, &p, &r, near, &mut packed, &mut out))
        .map_err(|e| sd_error(py, e))?;
    drop(packed);
    let m = 6 * n;
    let side = if rotation { m } else { 3 * n };
    if !rotation {
        for i in 0..side {
            out.copy_within(i * m..i * m + side, i * side);
        }
        out.truncate(side * side);
    }
    Ok(Array2::from_shape_vec((side, side), out)
        .expect("side * side values")
        .into_pyarray(py))
}

/// The kernel's refusal as a `ValueError`.
fn sd_error(py: Python<'_>, e: SdError) -> PyErr {
    match e {
        SdError::Particle(p) => particle_error(py, p),
        SdError::Near { i, j, why } if i == j => PyValueError::new_err(format!(
            "particle {i}: no near-field wall resistance ({why:?})"
        )),
        SdError::Near { i, j, why } => PyValueError::new_err(format!(
            "particles {i} and {j}: no near-field pair resistance ({why:?}; the size \
             ratio of a pair closer than the cutoff must be within 0.1 to 10)"
        )),
        SdError::NotPositiveDefinite(l) => PyValueError::new_err(format!(
            "the near-field resistance is not positive definite in this precision ({l})"
        )),
        SdError::Far(e) => PyValueError::new_err(format!("far field: {e}")),
        SdError::Params | SdError::Storage | SdError::NotConverged { .. } => {
            PyValueError::new_err(format!("near-field mobility refused: {e:?}"))
        }
    }
}
