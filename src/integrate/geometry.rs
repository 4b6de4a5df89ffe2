//! The mobility of the geometry a [`Params`] names (free space, above its wall
//! [`Params::wall`], in its periodic box [`Params::periodic`]) on its own: the matrix
//! and its product without a step, for front ends that hand them out (the Python
//! package's `mobility` and `mobility_dot`). The same functions the steps assemble
//! with, after the same refusals (a box with a wall, with rotation or with Oseen; a
//! radius not below half the box's smallest edge), so a front end cannot get a matrix
//! no step would use.

use super::checks::{check_box, check_slit_place};
use super::stages::{HeldSums, Sums, assemble_tt, free_product, held_ewald, hydro};
use crate::error::StepError;
use crate::linalg::tri;
use crate::parallel::{Parallel, band_scratch};
use crate::params::Params;
use crate::real::Real;

/// Refuses what a step would refuse of this geometry (every sphere is checked by the
/// mobility itself: finite, radius > 0, no nesting, above the wall).
/// Returns the box's Ewald parameters when there is one.
fn check<T: Real>(p: &Params<T>, radius: &[T]) -> Result<HeldSums<T>, StepError> {
    if !(p.viscosity > T::ZERO && p.viscosity.is_finite()) {
        return Err(StepError::BadParameter("viscosity"));
    }
    if p.place().wall().is_some_and(|h| !h.is_finite()) {
        return Err(StepError::BadParameter("wall.height (finite)"));
    }
    check_slit_place(p)?;
    check_box(p, radius)
}

/// `mu_tt` (`n x n` blocks, packed lower triangle: [`tri`]`(n)` blocks of `out`).
pub fn mobility_tt<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), StepError> {
    let sums = check(p, radius)?;
    assemble_tt(
        p,
        held_ewald(&sums),
        pos,
        radius,
        crate::linalg::MobMut::Full(&mut out[..tri(pos.len())]),
    )
}

/// The grand mobility (`2n x 2n` blocks, translations then rotations, packed as
/// [`crate::mobility::assemble_grand`] stores it: [`tri`]`(2n)` blocks of `out`): free space,
/// above the wall or in the box.
pub fn mobility_grand<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), StepError> {
    let sums = check(
        &Params {
            rotation: true,
            ..*p
        },
        radius,
    )?;
    grand(p, held_ewald(&sums), pos, radius, out)
}

/// The grand mobility of free space, above the wall or in the box (the checks done,
/// `ew` the box's Ewald sums): the one place that picks between the three
/// ([`mobility_grand`], `RattleStable` with rotation).
pub(super) fn grand<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), StepError> {
    let out = &mut out[..tri(2 * pos.len())];
    hydro(p, ew).assemble_grand(pos, radius, out)
}

/// `u = mu_tt f` without storing `mu_tt`, as a matrix-free step computes it. In free
/// space in the bands of [`crate::parallel`] through `par` (`scratch` holds
/// [`band_scratch`]`(n)` vectors, [`crate::parallel::free_product`]): the bits of the
/// stored mobility's banded product on any number of threads, above a wall too
/// ([`crate::mobility::wall::free_product`]). In a box: serial.
pub fn mobility_product<T: Real>(
    p: &Params<T>,
    par: &dyn Parallel,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    u: &mut [T::V3],
    scratch: &mut [T::V3],
) -> Result<(), StepError> {
    let sums = check(p, radius)?;
    let n = pos.len();
    let scratch = &mut scratch[..band_scratch(n)];
    let (f, u) = (&f[..n], &mut u[..n]);
    free_product(p, held_ewald(&sums), pos, radius, f, u, (par, scratch))
}
