//! `mobility_dot(..., method="fast")` in free space: the kernel's fast free-space RPY
//! product (`mobility::free_fast`, `O(N log N)`), sized from the spheres' bounding box
//! and largest radius, its storage checked against the machine before it is allocated.

use hydrorattle::mobility::free_fast::{FreeError, FreeFast, FreeStorage};
use hydrorattle::{Hydro, Real};
use hydrorattle_host::scene::DEFAULT_FREE_TOLERANCE;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::alloc;
use crate::errors::particle_error;

/// What `method = "fast"` cannot serve, as a `ValueError` saying why: a box, a wall,
/// another level; and its tolerance (default
/// [`DEFAULT_FREE_TOLERANCE`]) out of the kernel's range.
pub fn check(
    wall: Option<f64>,
    cell: Option<[f64; 3]>,
    level: Hydro,
    tolerance: Option<f64>,
) -> PyResult<f64> {
    let refuse = |why: &str| Err(PyValueError::new_err(format!("method=\"fast\" {why}")));
    if cell.is_some() {
        return refuse("is the free-space product: in a box use method=\"pse\"");
    }
    if wall.is_some() {
        return refuse("is the free-space product: above a wall use method=\"dense\"");
    }
    if level != Hydro::Rpy {
        return refuse("gives the RPY product only: hydro=\"rpy\"");
    }
    let tolerance = tolerance.unwrap_or(DEFAULT_FREE_TOLERANCE);
    let range = hydrorattle::mobility::free_fast::MIN_TOLERANCE
        ..=hydrorattle::mobility::free_fast::MAX_TOLERANCE;
    if !range.contains(&tolerance) {
        return Err(PyValueError::new_err(format!(
            "tolerance must be between {:e} and {} (the fast product's relative error), not {tolerance}",
            range.start(),
            range.end()
        )));
    }
    Ok(tolerance)
}

/// A refusal of the fast product as the package raises it: a sphere as the other
/// products name it, the rest a `ValueError` with the kernel's message.
fn free_error(py: Python<'_>, e: FreeError) -> PyErr {
    match e {
        FreeError::Particle(p) => particle_error(py, p),
        e => PyValueError::new_err(e.to_string()),
    }
}

/// The grand product's torques in and rotations out.
pub type Grand<'a, T> = (&'a [<T as Real>::V3], &'a mut [<T as Real>::V3]);

/// `u = M f` of the spheres at `pos` (radii `radius`, viscosity `eta`) by the fast
/// free-space product to `tolerance`, with the GIL released; with `grand` (torques `t`
/// and rotations `w`) the grand product `(u, w) = M (f, t)`.
#[allow(clippy::too_many_arguments)]
pub fn product<T: Real>(
    py: Python<'_>,
    tolerance: f64,
    eta: f64,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    u: &mut [T::V3],
    grand: Option<Grand<'_, T>>,
) -> PyResult<()> {
    if pos.is_empty() {
        return Ok(());
    }
    let fail = |e| free_error(py, e);
    let a_max = radius.iter().fold(T::ZERO, |m, &a| m.max(a));
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &p in pos {
        let p = T::v3_to_f64(p);
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    // A hair over the bounding box: the edges rounded to `T` must still hold it.
    let extent: [f64; 3] = std::array::from_fn(|d| (hi[d] - lo[d]).max(0.0) * (1.0 + 1e-6));
    let (extent, n) = (extent.map(T::from_f64), pos.len());
    let ff = match grand {
        Some(_) => FreeFast::new_grand(a_max, tolerance, extent, n),
        None => FreeFast::new(a_max, tolerance, extent, n),
    }
    .map_err(fail)?;
    let need = match grand {
        Some(_) => ff.storage_grand(n),
        None => ff.storage(n),
    };
    let what = format!("mobility_dot of {} spheres by the fast product", pos.len());
    alloc::Need::new(&what)
        .add::<[T; 2]>("grid", Some(need.complex))
        .add::<T>("kernel", Some(need.reals))
        .add::<usize>("cell list", Some(need.index))
        .check()?;
    let mut complex = alloc::filled(&what, "grid", need.complex, [T::ZERO; 2])?;
    let mut reals = alloc::filled(&what, "kernel", need.reals, T::ZERO)?;
    let mut index = alloc::filled(&what, "cell list", need.index, 0usize)?;
    py.detach(|| {
        let mut store = FreeStorage::new(&mut complex, &mut reals, &mut index);
        let eta = T::from_f64(eta);
        match grand {
            Some((t, w)) => ff.apply_grand(eta, (pos, radius), f, t, u, w, &mut store),
            None => ff.apply(eta, pos, radius, f, u, &mut store),
        }
    })
    .map_err(fail)
}
