//! The metric applied to a whole multiplier vector at once, `sum_l c_l D_l`: the
//! Krylov solver's product. The hydrodynamic metrics spread the multipliers into forces
//! and make one mobility product (stored, its compact copy, matrix-free, or in the
//! box), the implicit drag one more Cholesky solve; the mass and dense metrics add the
//! moves directly. It never forms an entry `D_l(p)` of a hydrodynamic metric, so it is
//! kept apart from the entry reads.

use super::Metric;
use crate::bonds::Bond;
use crate::linalg::{self, with_blocks};
use crate::real::Real;

/// `y <- S^-1 dt K^-1 S y` with `K = dt I + S mu S` factorised in `fac`.
pub(crate) fn apply_drag<T: Real>(fac: &[T::M3], sq: &[T], dt: T, y: &mut [T::V3]) {
    for (v, &q) in y.iter_mut().zip(sq) {
        *v *= q;
    }
    linalg::cholesky_solve::<T>(fac, sq.len(), y);
    for (v, &q) in y.iter_mut().zip(sq) {
        *v *= dt / q;
    }
}

impl<T: Real> Metric<'_, T> {
    /// `out = sum_l c_l D_l` over all bonds at once (the Krylov solver's product):
    /// `G^T c`, then one mobility product (and one drag solve). `tmp` holds at least
    /// `2m` vectors (`m` block rows of the mobility), and for [`Metric::Mobility`] and
    /// [`Metric::Free`] `n` and the product's
    /// [`band_scratch`](crate::parallel::band_scratch).
    pub fn apply_all(&self, bonds: &[Bond<T>], c: &[T], out: &mut [T::V3], tmp: &mut [T::V3]) {
        let n = out.len();
        match *self {
            Metric::Mass {
                inv_mass,
                grad,
                scale,
            } => {
                out.fill(T::V3_ZERO);
                for (l, b) in bonds.iter().enumerate() {
                    let g = grad[l] * (c[l] * scale);
                    out[b.i] += g * inv_mass[b.i];
                    if !b.one_sphere() {
                        out[b.j] -= g * inv_mass[b.j];
                    }
                }
            }
            Metric::Dense { .. } => {
                out.fill(T::V3_ZERO);
                self.apply_each(bonds, c, out);
            }
            Metric::Mobility {
                mu,
                grad,
                scale,
                par,
                compact,
            } => {
                let (f, bands) = tmp.split_at_mut(n);
                spread(bonds, grad, c, scale, f);
                match compact {
                    Some(copy) => crate::noise::reduced::apply::<T>(par, copy, n, f, out, bands),
                    None => {
                        with_blocks!(mu, a => crate::parallel::product::<T>(par, a, n, f, out, bands))
                    }
                }
            }
            Metric::Free {
                hydro,
                pos,
                radius,
                grad,
                scale,
                par,
            } => {
                let (f, bands) = tmp.split_at_mut(n);
                spread(bonds, grad, c, scale, f);
                // Nested pairs were refused by the product at these positions.
                if hydro.product(par, pos, radius, f, out, bands).is_err() {
                    out.fill(T::V3_ZERO);
                }
            }
            Metric::Drag {
                mu,
                fac,
                sq,
                dt,
                grad,
            } => {
                let m = sq.len();
                let (f, u) = tmp[..2 * m].split_at_mut(m);
                f.fill(T::V3_ZERO);
                spread(bonds, grad, c, T::ONE, &mut f[..n]);
                linalg::sym_matvec::<T>(mu, m, f, u);
                apply_drag(fac, sq, dt, u);
                for (o, &v) in out.iter_mut().zip(u.iter()) {
                    *o = v * dt;
                }
            }
        }
    }
}

impl<T: Real> Metric<'_, T> {
    /// `f = scale G^T c`, the forces the multipliers `c` put on the beads, for the
    /// hydrodynamic metrics ([`Metric::Mobility`], [`Metric::Free`]: their products are
    /// a mobility times these); `false`, `f` untouched, for the others. What a product
    /// of another mobility along this metric's gradients takes
    /// ([`Products`](crate::constraints::Products)).
    pub fn forces(&self, bonds: &[Bond<T>], c: &[T], f: &mut [T::V3]) -> bool {
        match *self {
            Metric::Mobility { grad, scale, .. } | Metric::Free { grad, scale, .. } => {
                spread(bonds, grad, c, scale, f);
                true
            }
            _ => false,
        }
    }
}

/// `f = scale G^T c`: the forces a multiplier vector puts on the beads.
fn spread<T: Real>(bonds: &[Bond<T>], grad: &[T::V3], c: &[T], scale: T, f: &mut [T::V3]) {
    f.fill(T::V3_ZERO);
    for (l, b) in bonds.iter().enumerate() {
        let g = grad[l] * (c[l] * scale);
        f[b.i] += g;
        if !b.one_sphere() {
            f[b.j] -= g;
        }
    }
}
