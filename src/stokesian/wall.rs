//! The wall's part of Stokesian dynamics: each close sphere's sphere-wall correction
//! (the exact resistance of `near/wall.rs` minus the inverse of the sphere's own wall
//! mobility block). Its far field is the wall's grand mobility, through the geometry
//! interface ([`Far::above`](super::Far::above)).

use super::{NearField, SdError};
use crate::mobility::wall::{self_wall, self_wall_rot};
use crate::near::wall::wall_scalars;
use crate::real::Real;

/// Adds each close sphere's wall correction to the resistance in `out`.
pub(super) fn add_walls<T: Real>(
    eta: T,
    height: T,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    out: &mut [T],
) -> Result<(), SdError> {
    let n = pos.len();
    let m = 6 * n;
    for (i, (&p, &a)) in pos.iter().zip(radius).enumerate() {
        let delta = (T::xyz(p)[2] - height) / a - T::ONE;
        if !(delta < near.wall_cutoff) {
            continue;
        }
        let delta = if delta < near.min_gap {
            near.min_gap
        } else {
            delta
        };
        let h = a * (T::ONE + delta);
        let w = wall_scalars(a, h).map_err(|why| SdError::Near { i, j: i, why })?;
        let pi = T::PI * eta;
        let (ta, ra) = (T::from_f64(6.0) * pi * a, T::from_f64(8.0) * pi * a * a * a);
        let b = T::from_f64(8.0) * pi * a * a * w.yb;
        // The far 6x6 self mobility decouples into z-translation, z-rotation and the two
        // (U_x, W_y), (U_y, W_x) pairs, whose 2x2 inverses are closed forms.
        let (par, perp) = self_wall(eta, a, h);
        let (rpar, rperp, c) = self_wall_rot(eta, a, h);
        let det = par * rpar - c * c;
        let (t, r) = (i, n + i);
        let mut put = |bi: usize, k: usize, bj: usize, l: usize, v: T| {
            out[(3 * bi + k) * m + 3 * bj + l] += v;
        };
        put(t, 2, t, 2, ta * w.xa - T::ONE / perp);
        put(r, 2, r, 2, ra * w.xc - T::ONE / rperp);
        for k in 0..2 {
            put(t, k, t, k, ta * w.ya - rpar / det);
            put(r, k, r, k, ra * w.yc - par / det);
        }
        // (U_x, W_y): exact -b, far -c / det; (U_y, W_x): +b and +c / det.
        let cross = b - c / det;
        for (k, l, sign) in [(0, 1, -T::ONE), (1, 0, T::ONE)] {
            put(t, k, r, l, sign * cross);
            put(r, l, t, k, sign * cross);
        }
    }
    Ok(())
}
