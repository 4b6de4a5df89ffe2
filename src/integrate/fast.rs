//! The fast free-space product's sizes for a host ([`fast_storage`], [`fast_vectors`])
//! and which steps take it ([`takes_fast`]); its parameters and products are the free
//! geometry's (`geometry/free/fast.rs`).

use crate::error::StepError;
pub use crate::geometry::free::fast::FAST_MARGIN;
use crate::geometry::free::fast::{fitted, params};
use crate::mobility::free_fast::{FreeError, FreeFast, FreeSize};
use crate::params::Params;
use crate::real::Real;

/// The fast free-space storage a step of the spheres at `pos` with radii `radius` needs
/// with `p` ([`Workspace::with_fast`](crate::Workspace::with_fast)): `Some` where the
/// step takes the fast free-space product ([`Params::pse`] with neither box nor wall,
/// at the RPY level), from the parameters the step derives for this cloud; `None` where
/// it needs none. A host sizes its arrays with it before the first step; as the cloud
/// moves, the step keeps within them (the module's documentation), so sizing from the
/// first configuration is enough. With [`Params::rotation`], or the iterative near field
/// ([`Params::near`] with [`Params::matrix_free`], whose far field is the grand product),
/// it is the grand product's
/// ([`FreeFast::storage_grand`](crate::mobility::free_fast::FreeFast::storage_grand)), and the step needs [`fast_vectors`] vectors too.
pub fn fast_storage<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
) -> Result<Option<FreeSize>, StepError> {
    match (takes_fast(p), p.pse) {
        (true, Some(tol)) => {
            if pos.len() != radius.len() {
                return Err(StepError::StateLength);
            }
            let fast = params((tol, grand(p)), pos, radius, [usize::MAX; 2])?;
            Ok(Some(match grand(p) {
                true => fast.storage_grand(pos.len()),
                false => fast.storage(pos.len()),
            }))
        }
        _ => Ok(None),
    }
}

/// The fast free-space parameters a step derives for `n` spheres of radius up to
/// `a_max` whose centres' bounding box has edges `box_edges`, with storage sized from
/// them (as [`fast_storage`] sizes it): [`FreeFast::new`]'s rule at tolerance `tol`
/// (with `rotation`, [`FreeFast::new_grand`]'s) over the box widened by
/// [`FAST_MARGIN`] radii and rounded, and where that grid passes its bounds (a long
/// chain along one axis) the spreading widened until one fits, as the step does.
/// For a host that weighs the product before it has positions (a cost model);
/// refused only where the step would refuse.
pub fn fast_parameters<T: Real>(
    tol: f64,
    rotation: bool,
    a_max: T,
    box_edges: [f64; 3],
    n: usize,
) -> Result<FreeFast<T>, FreeError> {
    fitted((tol, rotation), a_max, box_edges, n, [usize::MAX; 2])
}

/// The vectors a fast free-space step of `n` spheres with `p` needs besides
/// [`fast_storage`] ([`Workspace::with_fast_vectors`](crate::Workspace::with_fast_vectors)):
/// `2 n` with the grand product ([`Params::rotation`], or the iterative near field: the
/// grand product's zero torques and its discarded velocities, for the spins
/// `W = M_rt F`), else none.
pub fn fast_vectors<T: Real>(p: &Params<T>, n: usize) -> usize {
    match takes_fast(p) && grand(p) {
        true => 2 * n,
        false => 0,
    }
}

/// Whether `p` names the fast free-space product: [`Params::pse`] in free space (no box,
/// no wall), with pair hydrodynamics (free draining has no pair blocks to replace).
pub(super) fn takes_fast<T: Real>(p: &Params<T>) -> bool {
    let place = p.place();
    p.pse.is_some()
        && place.cell().is_none()
        && place.surfaces().is_empty()
        && p.hydro != crate::mobility::Hydro::FreeDraining
}

/// Whether a fast free-space step takes the grand product: for the spins
/// ([`Params::rotation`]), or as the iterative near field's far field ([`Params::near`]
/// with [`Params::matrix_free`], `near_iter/solve.rs`).
pub(super) const fn grand<T: Real>(p: &Params<T>) -> bool {
    p.rotation || (p.near_on() && p.matrix_free)
}
