//! PSE Brownian noise: a displacement with covariance `M` (the caller scales it by
//! `sqrt(2 kT dt)`), without any `O(N^2)` object: the wave part from white noise on the
//! grid through the square root of the wave-space kernel (`wave::apply_sqrt_kernel`,
//! exact: the same discrete operator as the product's), the real part by a Lanczos
//! square root (`noise::lanczos`) of the near-field operator through its products.
//! The near field is positive definite only for `xi a_max` well below 0.94 with this
//! split (`docs/PERIODIC.md`); where it is not, Lanczos reports it.

use super::{Part, Pse, PseError, PseStorage, Source, Spheres, near};
use crate::noise::Noise;
use crate::noise::lanczos::{self, Lanczos};
use crate::real::Real;

impl<T: Real> Pse<T> {
    /// Vectors and scalars [`Pse::noise`] needs beyond [`Pse::storage`]: the Lanczos
    /// basis for `s.max_iterations` and one standard normal vector per sphere.
    pub fn noise_storage(s: &Lanczos<T>, n: usize) -> (usize, usize) {
        let cap = s.max_iterations as usize;
        (lanczos::vectors(cap, n) + n, lanczos::scalars(cap))
    }

    /// `out` = a Gaussian displacement with covariance `M` (to the tolerance of the
    /// product and of `s`): `(M^real)^{1/2} z` by Lanczos from `n` standard normal
    /// vectors `z` drawn first, then the wave part from `3 M_grid` normals drawn in
    /// grid order. Returns the Lanczos iterations. `basis` and `work` hold at least
    /// [`Pse::noise_storage`].
    #[allow(clippy::too_many_arguments)]
    pub fn noise(
        &self,
        eta: T,
        (pos, radius): (&[T::V3], &[T]),
        rng: &mut Noise,
        s: Lanczos<T>,
        out: &mut [T::V3],
        store: &mut PseStorage<'_, T>,
        (basis, work): (&mut [T::V3], &mut [T]),
    ) -> Result<u32, PseError> {
        let n = pos.len();
        let (vectors, scalars) = Self::noise_storage(&s, n);
        if basis.len() < vectors || work.len() < scalars {
            return Err(PseError::Storage {
                need: [vectors, scalars, 0],
                have: [basis.len(), work.len(), 0],
            });
        }
        let (basis, z) = basis.split_at_mut(vectors - n);
        self.noise_in(eta, (pos, radius), rng, s, z, out, store, (basis, work))
    }

    /// [`Pse::noise`] with the `n` deviates `z` of the real part in the caller's array
    /// (a step keeps them in its own vectors) and `basis` of [`lanczos::vectors`]`(cap,
    /// n)` vectors. The deviates of both parts are one draw ([`Noise::fill_parts`]: a
    /// split generator's bridge spans both) taken before anything else; on error `out`
    /// is unspecified and `rng` has moved on (a step draws from a copy).
    #[allow(clippy::too_many_arguments)]
    pub fn noise_in(
        &self,
        eta: T,
        (pos, radius): (&[T::V3], &[T]),
        rng: &mut Noise,
        s: Lanczos<T>,
        z: &mut [T::V3],
        out: &mut [T::V3],
        store: &mut PseStorage<'_, T>,
        (basis, work): (&mut [T::V3], &mut [T]),
    ) -> Result<u32, PseError> {
        let n = pos.len();
        out.fill(T::V3_ZERO);
        let size = self.storage(n);
        self.check(eta, (pos, radius), (out, None), out, size, store)?;
        if n == 0 {
            return Ok(0);
        }
        let cap = s.max_iterations as usize;
        let (vectors, scalars) = (lanczos::vectors(cap, n), lanczos::scalars(cap));
        if basis.len() < vectors || work.len() < scalars || z.len() < n {
            return Err(PseError::Storage {
                need: [vectors + n, scalars, 0],
                have: [basis.len() + z.len(), work.len(), 0],
            });
        }
        // The grid is the wave stage's alone: the near field's products leave it be.
        let [mx, my, mz] = self.grid.m;
        let z = &mut z[..n];
        rng.fill_parts::<T>(z, &mut store.complex[..3 * mx * my * mz]);
        let mut failed = None;
        let product = |v: &[T::V3], w: &mut [T::V3]| {
            if failed.is_none()
                && let Err(e) = self.apply(Part::Near, eta, pos, radius, v, w, store)
            {
                failed = Some(e);
            }
        };
        let result = lanczos::sqrt(s, product, z, basis, work, out, None);
        if let Some(e) = failed {
            return Err(e);
        }
        let iterations = result.map_err(PseError::Lanczos)?;
        let (order, start) = store.index.split_at_mut(n);
        near::build(self, pos, order, start);
        let spheres = Spheres {
            pos,
            radius,
            order: &*order,
        };
        let rows = &mut store.vectors[..n];
        let work = (&mut *store.complex, rows, store.parallel);
        self.wave(eta, spheres, Source::Noise, work, (out, None));
        Ok(iterations)
    }
}
