//! Input arrays checked and converted: `(N, 3)` positions, `(N,)` radii, densities.
//! The Python layer hands C-contiguous float64 arrays (converting other dtypes and
//! layouts); they are read here without a copy.

use hydrorattle::cell_list::{check_pairs_in, indices};
use hydrorattle::particles::check_one;
use hydrorattle::{Particle, ParticleError, Periodic, Real};
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::{particle_error, particle_message};

/// The `(N, 3)` rows of `a` as `[x, y, z]` (a `ValueError` for another shape).
pub fn rows<'a>(a: &'a PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<&'a [[f64; 3]]> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{what} must have shape (N, 3), not {shape:?}"
        )));
    }
    let flat = a
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{what} must be C-contiguous")))?;
    let (chunks, rest) = flat.as_chunks::<3>();
    debug_assert!(rest.is_empty());
    Ok(chunks)
}

/// The `(n,)` values of `a` (a `ValueError` for another length).
pub fn column<'a>(a: &'a PyReadonlyArray1<'_, f64>, what: &str, n: usize) -> PyResult<&'a [f64]> {
    let v = a
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{what} must be contiguous")))?;
    if v.len() != n {
        return Err(PyValueError::new_err(format!(
            "{what} must have shape ({n},) to match the positions, not ({},)",
            v.len()
        )));
    }
    Ok(v)
}

/// Positions and radii in precision `T`, each particle checked by the kernel (finite,
/// radius > 0, density >= 0) and every pair (no sphere inside another; overlaps are
/// allowed): a `ValueError` naming the particle otherwise. The pairs through the
/// kernel's cell list (`O(N)` for spheres spread in space), with the all-pairs answer.
pub fn spheres<T: Real>(
    py: Python<'_>,
    pos: &[[f64; 3]],
    radii: &[f64],
    densities: Option<&[f64]>,
) -> PyResult<(Vec<T::V3>, Vec<T>)> {
    let (p, r) = each_sphere::<T>(py, pos, radii, densities)?;
    let mut cells = vec![0; indices(p.len())];
    check_pairs_in(&p, &r, true, &mut cells).map_err(|e| particle_error(py, e))?;
    Ok((p, r))
}

/// [`spheres`] without the check of every pair (`O(N^2)`), for the PSE product, whose
/// near field refuses a sphere inside another's image itself in `O(N)`.
pub fn each_sphere<T: Real>(
    py: Python<'_>,
    pos: &[[f64; 3]],
    radii: &[f64],
    densities: Option<&[f64]>,
) -> PyResult<(Vec<T::V3>, Vec<T>)> {
    let mut p = Vec::with_capacity(pos.len());
    let mut r = Vec::with_capacity(pos.len());
    for (k, (&x, &a)) in pos.iter().zip(radii).enumerate() {
        let d = densities.map_or(0.0, |d| d[k]);
        let q = Particle::new(T::v3_from(x), T::from_f64(a), T::from_f64(d));
        check_one(k, &q).map_err(|e| particle_error(py, e))?;
        p.push(q.position);
        r.push(q.radius);
    }
    Ok((p, r))
}

/// A positive, finite viscosity.
pub fn viscosity(eta: f64) -> PyResult<f64> {
    if eta.is_finite() && eta > 0.0 {
        Ok(eta)
    } else {
        Err(PyValueError::new_err(format!(
            "viscosity must be finite and > 0, not {eta}"
        )))
    }
}

/// The kernel's hydrodynamic level from its name (the kernel's names; `free_draining`
/// too, the Python spelling of `free-draining` that earlier releases accepted).
pub fn hydro(name: &str) -> PyResult<hydrorattle::Hydro> {
    match name {
        "free_draining" => Ok(hydrorattle::Hydro::FreeDraining),
        _ => crate::params::pick("hydro", name),
    }
}

/// `true` for "f32", `false` for "f64".
pub fn is_f32(precision: &str) -> PyResult<bool> {
    match precision {
        "f64" | "float64" => Ok(false),
        "f32" | "float32" => Ok(true),
        _ => Err(PyValueError::new_err(format!(
            "precision must be 'f64' or 'f32', not {precision:?}"
        ))),
    }
}

/// The periodic box of edges `edges` in precision `T`: finite, positive edges whose
/// volume `T` holds (the Ewald and PSE parameters derive from it); a `ValueError`
/// saying which otherwise.
pub fn cell<T: Real>(edges: [f64; 3]) -> PyResult<Periodic<T>> {
    let c = Periodic::new(edges.map(T::from_f64))
        .map_err(|e| PyValueError::new_err(format!("box: {e}")))?;
    if !c.volume().is_finite() {
        return Err(PyValueError::new_err(format!(
            "box: edges {edges:?} are too large: their volume overflows {} (the Ewald and PSE parameters derive from it)",
            std::any::type_name::<T>()
        )));
    }
    Ok(c)
}

/// Spheres in the box `edges`, checked as the CLI checks a scene's: every radius below
/// half the smallest edge (a sphere would overlap its own image), and every centre
/// within `1 / sqrt(eps)` edges of the origin in precision `T` (farther, its place in
/// the box, all the minimum image sees, keeps less than half its digits, and spheres
/// far apart look nested). A `ValueError` naming the particle (`index`) otherwise;
/// NaN passes here, for the particle check to name it.
pub fn in_box<T: Real>(
    py: Python<'_>,
    edges: [f64; 3],
    pos: &[[f64; 3]],
    radii: &[f64],
) -> PyResult<()> {
    let half = edges.iter().fold(f64::INFINITY, |m, &l| m.min(l)) / 2.0;
    if let Some(k) = radii.iter().position(|&a| a >= half) {
        return Err(particle_message(
            py,
            format!(
                "particle {k} has radius {}, not below half the box's smallest edge ({half}): it would overlap its own image",
                radii[k]
            ),
            k,
            ParticleError::BadRadius { particle: k },
        ));
    }
    let reach = 1.0 / T::EPSILON.to_f64().sqrt();
    for (k, x) in pos.iter().enumerate() {
        if let Some(d) = (0..3).find(|&d| x[d].abs() > reach * edges[d]) {
            return Err(particle_message(
                py,
                format!(
                    "particle {k} is at {:?}, more than {reach:.3e} box edges ({}) from the origin along axis {d}: in {} its place in the box would keep less than half its digits",
                    x,
                    edges[d],
                    std::any::type_name::<T>()
                ),
                k,
                ParticleError::NonFinite { particle: k },
            ));
        }
    }
    Ok(())
}
