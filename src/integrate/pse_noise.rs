//! Thermal noise on the PSE path ([`Params::pse`]): PSE's own draw
//! ([`Pse::noise_in`](crate::mobility::pse::Pse::noise_in): the real part by Lanczos on
//! the sparse near field, the wave part from white noise on the grid), so no product
//! with the whole mobility is taken for the square root and nothing `O(N^2)` exists.
//!
//! PSE's square root `L` (`L L^T = M`, `L w` the draw from the deviates `w` of both
//! parts) is not square, so there is no `L^-T w` for the Fixman midpoint. What the
//! midpoint needs of it is `E[(L w) v^T] = I` and `cov v = M^-1`; `v = M^-1 (L w)`
//! has both (`E[L w w^T L^T] M^-1 = I`, `M^-1 M M^-1 = M^-1`), so the midpoint solves
//! `M v = L w` by conjugate gradients with PSE products. It is needed only with bonds
//! (`brownian::kick` leaves it out otherwise: the box's mobility is divergence-free).

use super::Start;
use crate::error::StepError;
use crate::geometry::fast::FastProduct;
use crate::noise::Noise;
use crate::params::{Drift, Params};
use crate::real::Real;

/// The step's deviate vectors, its midpoint and its displacement ([`draw`]).
type Vectors<'a, T> = (
    &'a mut [<T as Real>::V3],
    &'a mut [<T as Real>::V3],
    &'a mut [<T as Real>::V3],
);

/// PSE's Brownian draw for one step, before scaling: `w` the real part's deviates
/// (the step's deviate vectors), then with [`Drift::Uncorrected`] `dx = L w`; with
/// [`Drift::Midpoint`] `mid = L w` and `w <- M^-1 L w` (the solve's residual in `dx`,
/// its directions in `basis`). Returns the Lanczos iterations plus the solve's.
#[allow(clippy::too_many_arguments)]
pub(super) fn draw<T: Real>(
    p: &Params<T>,
    drift: Drift,
    s: &Start<'_, T>,
    sums: &dyn FastProduct<T>,
    noise: &mut Noise,
    (w, mid, dx): Vectors<'_, T>,
    basis: &mut [T::V3],
    work: &mut [T],
) -> Result<u32, StepError> {
    let spheres = (s.pos, s.radius);
    let eta = p.viscosity;
    let out = match drift {
        Drift::Uncorrected => &mut *dx,
        Drift::Midpoint => &mut *mid,
    };
    let draws = sums.noise(eta, spheres, noise, p.lanczos, w, out, (&mut *basis, work))?;
    if drift == Drift::Uncorrected {
        return Ok(draws);
    }
    let solved = solve(p, s, sums, mid, w, dx, basis)?;
    Ok(draws + solved)
}

/// `x = M^-1 b` by conjugate gradients from `x = 0`, products by `sums`, to the
/// relative residual `|b - M x| <= tol |b|` (`tol` the Lanczos tolerance, the noise's
/// own accuracy) within four times the Lanczos iteration cap (the solve stores no
/// basis; `M` of 10^3 to 10^4 spheres apart at volume fraction 0.1 took 32 and 55
/// iterations at `1e-3`); `r` holds the residual, `basis`
/// (at least `2 n` vectors) the direction and its product. Sums in a fixed order.
fn solve<T: Real>(
    p: &Params<T>,
    s: &Start<'_, T>,
    sums: &dyn FastProduct<T>,
    b: &[T::V3],
    x: &mut [T::V3],
    r: &mut [T::V3],
    basis: &mut [T::V3],
) -> Result<u32, StepError> {
    let n = b.len();
    if basis.len() < 2 * n {
        return Err(StepError::BadParameter("lanczos.max_iterations (> 0)"));
    }
    let (d, q) = basis.split_at_mut(n);
    let q = &mut q[..n];
    let dot = |a: &[T::V3], c: &[T::V3]| {
        a.iter()
            .zip(c)
            .fold(T::ZERO, |t, (&u, &v)| t + T::dot(u, v))
    };
    x.fill(T::V3_ZERO);
    r.copy_from_slice(b);
    d.copy_from_slice(b);
    let goal = p.lanczos.tolerance * p.lanczos.tolerance * dot(b, b);
    let mut rr = dot(r, r);
    let cap = 4 * p.lanczos.max_iterations;
    let mut k = 0;
    while rr > goal {
        if k == cap {
            return Err(StepError::NoConvergence {
                stage: crate::error::Stage::Mobility,
                iterations: k,
                residual: (rr / dot(b, b)).sqrt().to_f64(),
            });
        }
        sums.product(p.viscosity, s.pos, s.radius, d, q)?;
        let dq = dot(d, q);
        if !(dq > T::ZERO) {
            // A direction of non-positive curvature: PSE's operator is positive
            // definite to its tolerance, so this is a configuration it cannot serve.
            return Err(StepError::Linalg {
                stage: crate::error::Stage::Mobility,
                error: crate::error::LinalgError::NotPositiveDefinite { row: 0 },
            });
        }
        let alpha = rr / dq;
        for i in 0..n {
            x[i] += d[i] * alpha;
            r[i] -= q[i] * alpha;
        }
        let next = dot(r, r);
        let beta = next / rr;
        for i in 0..n {
            d[i] = r[i] + d[i] * beta;
        }
        rr = next;
        k += 1;
    }
    Ok(k)
}
