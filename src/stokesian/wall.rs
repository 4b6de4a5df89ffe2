//! The wall's part of Stokesian dynamics: each close sphere's sphere-wall correction
//! (the exact resistance of `near/wall.rs` minus the inverse of the sphere's own wall
//! mobility block). Its far field is the wall's grand mobility, through the geometry
//! interface ([`Far::above`](super::Far::above)). The dense mobility adds the
//! corrections to its resistance ([`add_walls`]); the iterative product factors each
//! beside the close pairs' (`iterative.rs`), its preconditioner reading the far block.

use super::{NearField, SdError, add_block};
use crate::mobility::wall::{self_wall, self_wall_rot};
use crate::near::wall::wall_scalars;
use crate::real::Real;

/// A sphere's 6x6 wall blocks, rows and columns `(translation, rotation)`: `[[tt, tr],
/// [rt, rr]]`.
pub type SphereBlocks<T> = [[<T as Real>::M3; 2]; 2];

/// Sphere `i`'s wall correction `R_near` and the far field's own 6x6 self block (RPY's
/// self term with its wall reflections) that it corrects, both at the sphere's gap
/// clamped to [`NearField::min_gap`]; `None` beyond [`NearField::wall_cutoff`].
#[allow(clippy::type_complexity)]
pub fn wall_correction<T: Real>(
    eta: T,
    height: T,
    (pos, radius): (&[T::V3], &[T]),
    near: NearField<T>,
    i: usize,
) -> Result<Option<(SphereBlocks<T>, SphereBlocks<T>)>, SdError> {
    let (p, a) = (pos[i], radius[i]);
    let delta = gap(height, p, a);
    if !(delta < near.wall_cutoff) {
        return Ok(None);
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
    let o = T::ZERO;
    let diag = |x: T, z: T| T::m3_cols(T::v3(x, o, o), T::v3(o, x, o), T::v3(o, o, z));
    // `z x`: rotation-translation coupling's shape (the far field's `rt = c z x`).
    let zx = T::m3_cross(T::v3(o, o, T::ONE));
    let tt = diag(ta * w.ya - rpar / det, ta * w.xa - T::ONE / perp);
    let rr = diag(ra * w.yc - par / det, ra * w.xc - T::ONE / rperp);
    // (U_x, W_y): exact -b, far -c / det; (U_y, W_x): +b and +c / det.
    let tr = zx * (b - c / det);
    let correction = [[tt, tr], [T::transpose(tr), rr]];
    let far_rt = zx * c;
    let far = [
        [diag(par, perp), T::transpose(far_rt)],
        [far_rt, diag(rpar, rperp)],
    ];
    Ok(Some((correction, far)))
}

/// The sphere's gap to the wall at `height`, in radii (`h / a - 1`).
pub(super) fn gap<T: Real>(height: T, p: T::V3, a: T) -> T {
    (T::xyz(p)[2] - height) / a - T::ONE
}

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
    for i in 0..n {
        let Some((c, _)) = wall_correction(eta, height, (pos, radius), near, i)? else {
            continue;
        };
        let idx = [i, n + i];
        for (bi, row) in c.iter().enumerate() {
            for (bj, &b) in row.iter().enumerate() {
                add_block::<T>(out, 6 * n, (idx[bi], idx[bj]), b);
            }
        }
    }
    Ok(())
}
