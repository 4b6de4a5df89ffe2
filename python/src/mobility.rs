//! The dense mobility matrix and its product with forces (and torques).

use hydrorattle::linalg::{sym_get, sym_matvec, tri};
use hydrorattle::mobility::{assemble_grand, assemble_tt, tt_product};
use hydrorattle::{Hydro, Real};
use numpy::ndarray::Array2;
use numpy::{Element, IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::particle_error;
use crate::input::{column, is_f32, rows, spheres};

/// The dense `(3N, 3N)` (or `(6N, 6N)` with rotation) mobility in precision `T`.
fn dense<'py, T: Real + Element>(
    py: Python<'py>,
    pos: &[[f64; 3]],
    radii: &[f64],
    eta: f64,
    level: Hydro,
    rotation: bool,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let (p, r) = spheres::<T>(py, pos, radii, None)?;
    let n = p.len();
    let blocks = if rotation { 2 * n } else { n };
    let mut packed = vec![T::M3_ZERO; tri(blocks)];
    let eta = T::from_f64(eta);
    let filled = py.detach(|| {
        if rotation {
            assemble_grand(level, eta, &p, &r, &mut packed)
        } else {
            assemble_tt(level, eta, &p, &r, &mut packed)
        }
    });
    filled.map_err(|e| particle_error(py, e))?;
    let m = 3 * blocks;
    let mut out = Array2::<T>::from_elem((m, m), T::ZERO);
    for bi in 0..blocks {
        for bj in 0..blocks {
            let b = sym_get::<T>(&packed, bi, bj);
            for r in 0..3 {
                for c in 0..3 {
                    out[(3 * bi + r, 3 * bj + c)] = T::m3_get(b, r, c);
                }
            }
        }
    }
    Ok(out.into_pyarray(py))
}

/// Dense mobility matrix; see the Python docstring of `hydrorattle.mobility`.
#[pyfunction]
#[pyo3(signature = (positions, radii, viscosity=1.0, hydro="rpy", rotation=false, precision="f64"))]
pub fn mobility<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f64>,
    radii: PyReadonlyArray1<'py, f64>,
    viscosity: f64,
    hydro: &str,
    rotation: bool,
    precision: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let pos = rows(&positions, "positions")?;
    let radii = column(&radii, "radii", pos.len())?;
    let eta = crate::input::viscosity(viscosity)?;
    let level = crate::input::hydro(hydro)?;
    Ok(if is_f32(precision)? {
        dense::<f32>(py, pos, radii, eta, level, rotation)?.into_any()
    } else {
        dense::<f64>(py, pos, radii, eta, level, rotation)?.into_any()
    })
}

/// `(N, 3)` rows of `T` as a NumPy array.
fn to_array<'py, T: Real + Element>(py: Python<'py>, v: &[T::V3]) -> Bound<'py, PyArray2<T>> {
    let flat: Vec<T> = v.iter().flat_map(|&x| T::xyz(x)).collect();
    Array2::from_shape_vec((v.len(), 3), flat)
        .expect("3 values per row")
        .into_pyarray(py)
}

/// Velocities (and spins) in precision `T`.
#[allow(clippy::too_many_arguments)]
fn product<'py, T: Real + Element>(
    py: Python<'py>,
    pos: &[[f64; 3]],
    radii: &[f64],
    forces: &[[f64; 3]],
    torques: Option<&[[f64; 3]]>,
    eta: f64,
    level: Hydro,
    rotation: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let (p, r) = spheres::<T>(py, pos, radii, None)?;
    let n = p.len();
    let eta = T::from_f64(eta);
    let f: Vec<T::V3> = forces.iter().map(|&x| T::v3_from(x)).collect();
    if torques.is_none() && !rotation {
        let mut u = vec![T::V3_ZERO; n];
        py.detach(|| tt_product(level, eta, &p, &r, &f, &mut u))
            .map_err(|e| particle_error(py, e))?;
        return Ok(to_array::<T>(py, &u).into_any());
    }
    // With rotation: the grand mobility packed (O(N^2) storage) and one product.
    let mut x = f;
    x.extend(torques.map_or_else(
        || vec![T::V3_ZERO; n],
        |t| t.iter().map(|&x| T::v3_from(x)).collect(),
    ));
    let mut y = vec![T::V3_ZERO; 2 * n];
    let mut packed = vec![T::M3_ZERO; tri(2 * n)];
    py.detach(|| {
        assemble_grand(level, eta, &p, &r, &mut packed)?;
        sym_matvec::<T>(&packed, 2 * n, &x, &mut y);
        Ok(())
    })
    .map_err(|e| particle_error(py, e))?;
    let u = to_array::<T>(py, &y[..n]);
    let w = to_array::<T>(py, &y[n..]);
    Ok((u, w).into_pyobject(py)?.into_any())
}

/// Mobility product; see the Python docstring of `hydrorattle.mobility_dot`.
#[pyfunction]
#[pyo3(signature = (positions, radii, forces, torques=None, viscosity=1.0, hydro="rpy", rotation=false, precision="f64"))]
#[allow(clippy::too_many_arguments)]
pub fn mobility_dot<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f64>,
    radii: PyReadonlyArray1<'py, f64>,
    forces: PyReadonlyArray2<'py, f64>,
    torques: Option<PyReadonlyArray2<'py, f64>>,
    viscosity: f64,
    hydro: &str,
    rotation: bool,
    precision: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let pos = rows(&positions, "positions")?;
    let radii = column(&radii, "radii", pos.len())?;
    let f = rows(&forces, "forces")?;
    if f.len() != pos.len() {
        return Err(PyValueError::new_err(format!(
            "forces must have shape ({}, 3) to match the positions, not ({}, 3)",
            pos.len(),
            f.len()
        )));
    }
    let t = match &torques {
        Some(t) => {
            let t = rows(t, "torques")?;
            if t.len() != pos.len() {
                return Err(PyValueError::new_err(format!(
                    "torques must have shape ({}, 3) to match the positions",
                    pos.len()
                )));
            }
            Some(t)
        }
        None => None,
    };
    let finite = |v: &[[f64; 3]]| v.iter().position(|x| !x.iter().all(|c| c.is_finite()));
    for (what, v) in [("forces", Some(f)), ("torques", t)] {
        if let Some(k) = v.and_then(finite) {
            return Err(PyValueError::new_err(format!(
                "particle {k}: non-finite {what}"
            )));
        }
    }
    let eta = crate::input::viscosity(viscosity)?;
    let level = crate::input::hydro(hydro)?;
    if is_f32(precision)? {
        product::<f32>(py, pos, radii, f, t, eta, level, rotation)
    } else {
        product::<f64>(py, pos, radii, f, t, eta, level, rotation)
    }
}
