//! Pinned spheres ([`Bond::pin`], `docs/CONTACTS.md`): the checks a step makes of its
//! pin rows, and the return of a pinned coordinate to its anchor after the solve.
//!
//! A pin row holds sphere `i` along one axis at its position at the start of the step
//! (the anchor): a linear equality solved with the bonds, so that its multiplier is the
//! force that holds the sphere, hydrodynamic interactions included (the mixed mobility
//! problem: `U_i = 0`, `F_i` unknown). The solve meets it to the tolerance; the step
//! then writes the anchor's coordinate back (and a zero velocity along it), so a
//! pinned sphere stays where the caller put it bit for bit, step after step.

use crate::bonds::Bond;
use crate::cell::image;
use crate::error::{BondError, ParticleError, StepError};
use crate::params::{Method, Params};
use crate::real::Real;

/// Refuses pin rows where they are not implemented, a sphere pinned twice along one
/// axis ([`BondError::Duplicate`]: dependent rows), and two pinned spheres that
/// overlap (neither can move, so no step could part them): `O(B + P^2)` for `P` pin
/// rows, nothing without any.
pub(super) fn check<T: Real>(
    p: &Params<T>,
    bonds: &[Bond<T>],
    pos: &[T::V3],
    radius: &[T],
    thermal: bool,
) -> Result<(), StepError> {
    if !cfg!(feature = "pins") || !bonds.iter().any(|b| b.is_pin()) {
        return Ok(());
    }
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return Err(StepError::Unsupported(
            "pinned spheres with a method other than Overdamped or Overdamped2",
        ));
    }
    if thermal {
        return Err(StepError::Unsupported("pinned spheres with thermal noise"));
    }
    let pins = || bonds.iter().enumerate().filter(|(_, b)| b.is_pin());
    for (k, b) in pins() {
        let same = |(_, o): &(usize, &Bond<T>)| o.i == b.i && o.j == b.j;
        if let Some((other, _)) = pins().take_while(|&(l, _)| l < k).find(same) {
            return Err(BondError::Duplicate { bond: k, other }.into());
        }
    }
    if p.allow_overlap {
        return Ok(());
    }
    // Touching pinned spheres are fine (a floor of touching spheres): overlap past the
    // tolerance the acceptance grants contacts is not.
    let reach = T::ONE - p.solver.tolerance * T::TWO;
    let cell = super::cell(p);
    let pins = || bonds.iter().filter(|b| b.is_pin()).map(|b| b.i);
    for (k, i) in pins().enumerate() {
        for j in pins().take(k) {
            if j == i {
                continue;
            }
            let sum = (radius[i] + radius[j]) * reach;
            if T::norm2(image(cell.as_ref(), pos[i] - pos[j])) < sum * sum {
                let (i, j) = (i.min(j), i.max(j));
                return Err(ParticleError::Overlap { i, j }.into());
            }
        }
    }
    Ok(())
}

/// Puts every pinned coordinate of the candidate back on its anchor (`start`), with a
/// zero velocity along it (the solve left it within the tolerance).
#[cfg(feature = "pins")]
pub(super) fn restore<T: Real>(
    bonds: &[Bond<T>],
    start: &[T::V3],
    pos: &mut [T::V3],
    vel: &mut [T::V3],
) {
    for b in bonds.iter().filter(|b| b.is_pin()) {
        let e = b.axis();
        let (mut x, mut v) = (T::xyz(pos[b.i]), T::xyz(vel[b.i]));
        x[e] = T::xyz(start[b.i])[e];
        v[e] = T::ZERO;
        pos[b.i] = T::v3(x[0], x[1], x[2]);
        vel[b.i] = T::v3(v[0], v[1], v[2]);
    }
}
