//! The dense mobility matrix and its product with forces (and torques), in free space,
//! above a wall or in a periodic box: the kernel's `integrate::geometry`, which refuses
//! what a step would refuse of the geometry.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use hydrorattle::integrate::geometry;
use hydrorattle::linalg::{sym_matvec, tri};
use hydrorattle::parallel::{band_scratch, bands};
use hydrorattle::{Hydro, Parallel, Params, Real, Serial, Wall};
use hydrorattle_parallel::Threads;
use numpy::ndarray::Array2;
use numpy::{Element, IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::alloc;
use crate::dense::write_dense;
use crate::errors::value_error;
use crate::input::{column, is_f32, rows, spheres};

/// The geometry's keyword arguments: `wall` (a height) and `box` (three edges).
#[derive(Clone, Copy)]
pub struct Geometry {
    wall: Option<f64>,
    cell: Option<[f64; 3]>,
}

impl Geometry {
    /// Kernel parameters in `T` naming the level, viscosity, wall and box (a bad box
    /// edge is a `ValueError` from the kernel's check).
    fn params<T: Real>(&self, eta: f64, level: Hydro, rotation: bool) -> PyResult<Params<T>> {
        let mut p = Params::<T>::new(T::ONE);
        p.viscosity = T::from_f64(eta);
        p.hydro = level;
        p.rotation = rotation;
        p.wall = self.wall.map(|h| Wall::new(T::from_f64(h)));
        if let Some(c) = self.cell {
            p.periodic = Some(crate::input::cell::<T>(c)?);
        }
        Ok(p)
    }

    /// The spheres checked against the box, if any ([`crate::input::in_box`]).
    fn spheres_fit(
        &self,
        py: Python<'_>,
        f32: bool,
        pos: &[[f64; 3]],
        radii: &[f64],
    ) -> PyResult<()> {
        match (self.cell, f32) {
            (Some(c), true) => crate::input::in_box::<f32>(py, c, pos, radii),
            (Some(c), false) => crate::input::in_box::<f64>(py, c, pos, radii),
            (None, _) => Ok(()),
        }
    }
}

/// `wall` and `box` from their Python values.
pub fn geometry(wall: Option<f64>, cell: Option<[f64; 3]>) -> Geometry {
    Geometry { wall, cell }
}

/// The dense `(3N, 3N)` (or `(6N, 6N)` with rotation) mobility in precision `T`.
#[allow(clippy::too_many_arguments)]
fn dense<'py, T: Real + Element>(
    py: Python<'py>,
    pos: &[[f64; 3]],
    radii: &[f64],
    eta: f64,
    level: Hydro,
    rotation: bool,
    g: Geometry,
    threads: usize,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let p = g.params::<T>(eta, level, rotation)?;
    let n = pos.len();
    let what = format!("mobility of {n} spheres");
    let blocks = if rotation { 2 * n } else { n };
    let side = blocks.checked_mul(3);
    let out_len = side.and_then(|m| m.checked_mul(m));
    alloc::Need::new(&what)
        .add::<T::M3>("packed blocks", alloc::packed(blocks))
        .add::<T>("output", out_len)
        .check()?;
    let (pos, r) = spheres::<T>(py, pos, radii, None)?;
    // Both arrays before any work. The output is NumPy's own zeros: fresh pages
    // (faulted by the bands in parallel), NumPy's `MemoryError` where they are refused.
    let m = 3 * blocks;
    let dtype = numpy::dtype::<T>(py);
    let array = py
        .import("numpy")?
        .call_method1("zeros", ((m, m), dtype))?
        .cast_into::<PyArray2<T>>()?;
    let mut packed = alloc::filled(&what, "packed blocks", tri(blocks), T::M3_ZERO)?;
    let filled = py.detach(|| match rotation {
        true => geometry::mobility_grand(&p, &pos, &r, &mut packed),
        false => geometry::mobility_tt(&p, &pos, &r, &mut packed),
    });
    filled.map_err(|e| value_error(py, e))?;
    let par = threads_for(blocks, threads)?;
    {
        let mut rw = array.readwrite();
        let out = rw.as_slice_mut()?;
        py.detach(|| write_dense::<T>(&packed, blocks, par_of(&par), out));
    }
    Ok(array)
}

/// Dense mobility matrix; see the Python docstring of `hydrorattle.mobility`.
#[pyfunction]
#[pyo3(signature = (positions, radii, viscosity=1.0, hydro="rpy", rotation=false, precision="f64", wall=None, r#box=None, threads=0, near_field=false))]
#[allow(clippy::too_many_arguments)]
pub fn mobility<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f64>,
    radii: PyReadonlyArray1<'py, f64>,
    viscosity: f64,
    hydro: &str,
    rotation: bool,
    precision: &str,
    wall: Option<f64>,
    r#box: Option<[f64; 3]>,
    threads: usize,
    near_field: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let pos = rows(&positions, "positions")?;
    let radii = column(&radii, "radii", pos.len())?;
    let eta = crate::input::viscosity(viscosity)?;
    let level = crate::input::hydro(hydro)?;
    if near_field {
        return near_field_mobility(py, pos, radii, eta, level, rotation, precision, wall, r#box);
    }
    let g = geometry(wall, r#box);
    g.spheres_fit(py, is_f32(precision)?, pos, radii)?;
    Ok(if is_f32(precision)? {
        dense::<f32>(py, pos, radii, eta, level, rotation, g, threads)?.into_any()
    } else {
        dense::<f64>(py, pos, radii, eta, level, rotation, g, threads)?.into_any()
    })
}

/// `mobility(..., near_field=True)`: RPY only, in free space, above the wall or in the box.
#[allow(clippy::too_many_arguments)]
fn near_field_mobility<'py>(
    py: Python<'py>,
    pos: &[[f64; 3]],
    radii: &[f64],
    eta: f64,
    level: Hydro,
    rotation: bool,
    precision: &str,
    wall: Option<f64>,
    cell: Option<[f64; 3]>,
) -> PyResult<Bound<'py, PyAny>> {
    if cell.is_some() && wall.is_some() {
        return Err(PyValueError::new_err(
            "near_field=True takes a wall or a box, not both",
        ));
    }
    if level != Hydro::Rpy {
        return Err(PyValueError::new_err(
            "near_field=True adds the near field to RPY: use hydro=\"rpy\"",
        ));
    }
    Ok(if is_f32(precision)? {
        crate::near::dense::<f32>(py, pos, radii, eta, rotation, wall, cell)?.into_any()
    } else {
        crate::near::dense::<f64>(py, pos, radii, eta, rotation, wall, cell)?.into_any()
    })
}

/// `(N, 3)` rows of `T` as a NumPy array.
fn to_array<'py, T: Real + Element>(py: Python<'py>, v: &[T::V3]) -> Bound<'py, PyArray2<T>> {
    let flat: Vec<T> = v.iter().flat_map(|&x| T::xyz(x)).collect();
    Array2::from_shape_vec((v.len(), 3), flat)
        .expect("3 values per row")
        .into_pyarray(py)
}

/// A pool of `threads` threads (0: every core), built once per count and kept.
pub fn pool(threads: usize) -> PyResult<Arc<Threads>> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<Threads>>>> = OnceLock::new();
    let mut pools = POOLS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(t) = pools.get(&threads) {
        return Ok(t.clone());
    }
    let t = Arc::new(
        Threads::new(threads).map_err(|e| PyValueError::new_err(format!("threads: {e}")))?,
    );
    pools.insert(threads, t.clone());
    Ok(t)
}

/// The pool for `n` block rows on `threads` threads: none below the kernel's banded
/// size ([`bands`]) or for one thread.
fn threads_for(n: usize, threads: usize) -> PyResult<Option<Arc<Threads>>> {
    match bands(n) > 1 && threads != 1 {
        true => Ok(Some(pool(threads)?)),
        false => Ok(None),
    }
}

/// The pool as the kernel's [`Parallel`], or the calling thread.
fn par_of(pool: &Option<Arc<Threads>>) -> &dyn Parallel {
    match pool {
        Some(t) => t.as_ref(),
        None => &Serial,
    }
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
    g: Geometry,
    threads: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let rotation = rotation || torques.is_some();
    let p = g.params::<T>(eta, level, rotation)?;
    let (pos, r) = spheres::<T>(py, pos, radii, None)?;
    let n = pos.len();
    let f: Vec<T::V3> = forces.iter().map(|&x| T::v3_from(x)).collect();
    if !rotation {
        let par = threads_for(n, threads)?;
        let mut u = vec![T::V3_ZERO; n];
        let mut z = vec![T::V3_ZERO; band_scratch(n)];
        py.detach(|| geometry::mobility_product(&p, par_of(&par), &pos, &r, &f, &mut u, &mut z))
            .map_err(|e| value_error(py, e))?;
        return Ok(to_array::<T>(py, &u).into_any());
    }
    // With rotation: the grand mobility packed (O(N^2) storage) and one product.
    let mut x = f;
    x.extend(torques.map_or_else(
        || vec![T::V3_ZERO; n],
        |t| t.iter().map(|&x| T::v3_from(x)).collect(),
    ));
    let what = format!("mobility_dot of {n} spheres with rotation");
    alloc::Need::new(&what)
        .add::<T::M3>("packed grand mobility", alloc::packed(2 * n))
        .check()?;
    let mut y = vec![T::V3_ZERO; 2 * n];
    let mut packed = alloc::filled(&what, "packed grand mobility", tri(2 * n), T::M3_ZERO)?;
    py.detach(|| {
        geometry::mobility_grand(&p, &pos, &r, &mut packed)?;
        sym_matvec::<T>(&packed, 2 * n, &x, &mut y);
        Ok(())
    })
    .map_err(|e| value_error(py, e))?;
    let u = to_array::<T>(py, &y[..n]);
    let w = to_array::<T>(py, &y[n..]);
    Ok((u, w).into_pyobject(py)?.into_any())
}

/// Mobility product; see the Python docstring of `hydrorattle.mobility_dot`.
#[pyfunction]
#[pyo3(signature = (positions, radii, forces, torques=None, viscosity=1.0, hydro="rpy", rotation=false, precision="f64", wall=None, r#box=None, threads=0, method="auto", tolerance=None))]
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
    wall: Option<f64>,
    r#box: Option<[f64; 3]>,
    threads: usize,
    method: &str,
    tolerance: Option<f64>,
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
    let g = geometry(wall, r#box);
    g.spheres_fit(py, is_f32(precision)?, pos, radii)?;
    let rotation = rotation || t.is_some();
    if method == "fast" {
        let tol = crate::free::check(wall, r#box, level, tolerance)?;
        let torques = rotation.then_some(t.unwrap_or(&[]));
        return match is_f32(precision)? {
            true => fast_product::<f32>(py, pos, radii, (f, torques), eta, tol),
            false => fast_product::<f64>(py, pos, radii, (f, torques), eta, tol),
        };
    }
    let asked = crate::pse::method(method, tolerance)?;
    if let Some(size) = r#box.filter(|_| wall.is_none()) {
        if crate::pse::uses_pse(asked, Some(size), radii, level, rotation)? {
            let pse = (size, asked.1);
            return Ok(match is_f32(precision)? {
                true => pse_product::<f32>(py, pos, radii, f, eta, pse, threads)?.into_any(),
                false => pse_product::<f64>(py, pos, radii, f, eta, pse, threads)?.into_any(),
            });
        }
    } else {
        crate::pse::uses_pse(asked, None, radii, level, rotation)?;
    }
    if is_f32(precision)? {
        product::<f32>(py, pos, radii, f, t, eta, level, rotation, g, threads)
    } else {
        product::<f64>(py, pos, radii, f, t, eta, level, rotation, g, threads)
    }
}

/// Velocities in precision `T` in the box `size` by PSE to `tolerance`: the spheres
/// checked one by one here, pairs by the near field (`O(N)`), the pieces run on
/// `threads` threads from the kernel's banded size on.
fn pse_product<'py, T: Real + Element>(
    py: Python<'py>,
    pos: &[[f64; 3]],
    radii: &[f64],
    forces: &[[f64; 3]],
    eta: f64,
    (size, tolerance): ([f64; 3], f64),
    threads: usize,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let (pos, r) = crate::input::each_sphere::<T>(py, pos, radii, None)?;
    let n = pos.len();
    let f: Vec<T::V3> = forces.iter().map(|&x| T::v3_from(x)).collect();
    let par = threads_for(n, threads)?;
    let mut u = vec![T::V3_ZERO; n];
    let par = par.as_deref();
    crate::pse::product::<T>(py, size, tolerance, eta, &pos, &r, &f, &mut u, par)?;
    Ok(to_array::<T>(py, &u))
}

/// Velocities in precision `T` in free space by the fast product to `tolerance`: the
/// spheres checked one by one here, pairs (one inside another) in its near part. With
/// rotation (`torques` `Some`, empty for none) the grand product: `(u, w)`.
fn fast_product<'py, T: Real + Element>(
    py: Python<'py>,
    pos: &[[f64; 3]],
    radii: &[f64],
    (forces, torques): (&[[f64; 3]], Option<&[[f64; 3]]>),
    eta: f64,
    tolerance: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let (pos, r) = crate::input::each_sphere::<T>(py, pos, radii, None)?;
    let n = pos.len();
    let v3 = |v: &[[f64; 3]]| -> Vec<T::V3> { v.iter().map(|&x| T::v3_from(x)).collect() };
    let f = v3(forces);
    let mut u = vec![T::V3_ZERO; n];
    let Some(t) = torques else {
        crate::free::product::<T>(py, tolerance, eta, &pos, &r, &f, &mut u, None)?;
        return Ok(to_array::<T>(py, &u).into_any());
    };
    let t = match t.is_empty() {
        true => vec![T::V3_ZERO; n],
        false => v3(t),
    };
    let mut w = vec![T::V3_ZERO; n];
    let grand = Some((&t[..], &mut w[..]));
    crate::free::product::<T>(py, tolerance, eta, &pos, &r, &f, &mut u, grand)?;
    let (u, w) = (to_array::<T>(py, &u), to_array::<T>(py, &w));
    Ok((u, w).into_pyobject(py)?.into_any())
}
