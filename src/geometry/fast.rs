//! What the fast products have in common, whichever geometry they serve (feature
//! `pse`): PSE's in a periodic box (`geometry/sums.rs`) and the fast free-space
//! product's (`geometry/free/fast.rs`, feature `fast-free`) give products and noise
//! only, over the caller's arrays (`Slices`), and the step's stages read either
//! through [`FastProduct`].

use crate::error::StepError;
use crate::mobility::fft::Cx;
use crate::noise::{Noise, lanczos::Lanczos};
use crate::real::Real;

/// The caller's fast products' arrays: complex values, indices, vectors (PSE's
/// storage) and reals (the fast free-space product's kernel).
pub(crate) type Slices<'a, T> = (
    &'a mut [Cx<T>],
    &'a mut [usize],
    &'a mut [<T as Real>::V3],
    &'a mut [T],
);

/// The grand product's `2n` forces then torques `ft` and velocities then spins `out`
/// as their halves (`FastProduct::grand`'s implementors), or the length error.
#[allow(clippy::type_complexity)]
pub(crate) fn grand_halves<'a, 'b, T: Real>(
    n: usize,
    ft: &'a [T::V3],
    out: &'b mut [T::V3],
) -> Result<
    (
        (&'a [T::V3], &'a [T::V3]),
        (&'b mut [T::V3], &'b mut [T::V3]),
    ),
    StepError,
> {
    match (
        ft.get(..2 * n).map(|v| v.split_at(n)),
        out.get_mut(..2 * n).map(|v| v.split_at_mut(n)),
    ) {
        (Some(ft), Some(out)) => Ok((ft, out)),
        _ => Err(StepError::StateLength),
    }
}

/// A product `u = M f` of a geometry's mobility over storage the implementor holds:
/// PSE's in a box ([`PseStep`](super::sums::PseStep)), the fast free-space product's
/// (`geometry/free/fast.rs`).
pub trait FastProduct<T: Real> {
    /// `u = M f` with viscosity `eta` for the spheres at `pos` with radii `radius`.
    fn product(
        &self,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        u: &mut [T::V3],
    ) -> Result<(), StepError>;

    /// `out = M_rt F`: the spins of torque-free spheres from the forces `f` they exert
    /// on the fluid. Only products that carry rotation give it (the fast free-space
    /// product with [`Params::rotation`](crate::Params::rotation)); the rest refuse.
    fn spin(
        &self,
        eta: T,
        spheres: (&[T::V3], &[T]),
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let _ = (eta, spheres, f, out);
        Err(StepError::Unsupported(
            "spins from a fast product without rotation (its rt products are not built)",
        ))
    }

    /// `out = M_grand ft`: the grand mobility (translations and rotations) applied to
    /// the `2n` forces then torques `ft`, velocities then spins into `out`: the far
    /// field of the iterative near field (`integrate/near_iter/solve.rs`). Only
    /// products that carry rotation give it (the fast free-space product's parameters
    /// for the grand product); the rest refuse.
    fn grand(
        &self,
        eta: T,
        spheres: (&[T::V3], &[T]),
        ft: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let _ = (eta, spheres, ft, out);
        Err(StepError::Unsupported(
            "the grand product of a fast product without rotation (its rt and rr products are not built)",
        ))
    }

    /// `out` = a Brownian displacement of covariance `M` by the sums' own noise
    /// (PSE's [`Pse::noise_in`](crate::mobility::pse::Pse::noise_in): the real part by Lanczos to `s` from the deviates `z`,
    /// the wave part from white noise on the grid), drawn from `rng`; `basis` and
    /// `work` hold the Lanczos basis. Returns the Lanczos iterations.
    #[allow(clippy::too_many_arguments)]
    fn noise(
        &self,
        eta: T,
        spheres: (&[T::V3], &[T]),
        rng: &mut Noise,
        s: Lanczos<T>,
        z: &mut [T::V3],
        out: &mut [T::V3],
        scratch: (&mut [T::V3], &mut [T]),
    ) -> Result<u32, StepError>;
}
