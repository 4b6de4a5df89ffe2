//! The near field's share of the Brownian noise: `L z` with `R_near = L L^T` the close
//! pairs' factors the product has already made ([`Solver::new`]), `z` twelve standard
//! normal deviates a pair. Its covariance is `R_near` exactly (no iteration): with the
//! far field's `M_far^(-1/2) z'` beside it, `b = M_far^(-1/2) z' + L z` has covariance
//! `M_far^-1 + R_near = R`, and `M_SD b` has covariance `M_SD R M_SD = M_SD`
//! (Fiore and Swan's split, `integrate::near_iter::noise`).

use super::pairs::slot;
use super::{B, K, Solver};
use crate::real::Real;

impl<T: Real> Solver<'_, T> {
    /// `b += L z` over the `2n` forces and torques, `z` drawn by `draw` four vectors (one
    /// pair's twelve deviates) at a time, pair by pair in the pairs' fixed order.
    pub fn add_near_noise(
        &self,
        draw: &mut dyn FnMut(&mut [T::V3; 4]),
        b: &mut [T::V3],
    ) -> Result<(), super::SdError> {
        let n = self.n;
        if b.len() < 2 * n {
            return Err(super::SdError::Storage);
        }
        for (&pair, fac) in self.pairs.iter().zip(self.factors.chunks_exact(2 * B)) {
            let mut v = [T::V3_ZERO; 4];
            draw(&mut v);
            let mut z = [T::ZERO; K];
            for (c, &x) in z.chunks_exact_mut(3).zip(&v) {
                c.copy_from_slice(&T::xyz(x));
            }
            // The factor is lower triangular, row-major (`pairs::factor_semidefinite`).
            let mut w = [T::ZERO; K];
            for (k, w) in w.iter_mut().enumerate() {
                *w = (0..=k).fold(T::ZERO, |s, m| s + fac[k * K + m] * z[m]);
            }
            for (k, w) in w.chunks_exact(3).enumerate() {
                b[slot(n, pair, k)] += T::v3(w[0], w[1], w[2]);
            }
        }
        Ok(())
    }
}
