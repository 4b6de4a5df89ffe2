//! One configuration of the iterative near field: the far field's grand mobility
//! assembled and the close pairs found and factored once, then every product the step
//! needs there (the velocities, and in a Brownian step the noise's solve and the far
//! field's products its Lanczos root takes).

use super::{Counts, STORAGE, Store, error, tri2};
use crate::error::StepError;
use crate::params::{NEAR_PAIRS_PER_SPHERE, Params};
use crate::real::Real;
use crate::stokesian::iterative::{Solver, Storage, packed_product};

use super::super::Sums;

/// The near field's products at one configuration ([`at`]).
pub(super) struct At<'s, T: Real> {
    n: usize,
    packed: &'s [T::M3],
    solver: Solver<'s, T>,
    /// The store's `2n` forces and torques, then `2n` velocities and spins.
    io: &'s mut [T::V3],
}

/// Runs `body` with the products at `(pos, radius)`: the grand mobility assembled into
/// the store's packed blocks, the close pairs factored into its reals.
pub(super) fn at<T: Real, R>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    (pos, radius): (&[T::V3], &[T]),
    store: &mut Store<'_, T>,
    body: impl FnOnce(&mut At<'_, T>) -> Result<R, StepError>,
) -> Result<R, StepError> {
    let n = pos.len();
    let Some(nf) = p.near else {
        return Err(StepError::Unsupported(
            "the near field's mobility without Params::near",
        ));
    };
    let far = super::super::near::far(p, ew)?;
    let packed = store.packed.get_mut(..tri2(n)).ok_or(STORAGE)?;
    far.assemble_grand(p.viscosity, pos, radius, packed)
        .map_err(error)?;
    let (io, field) = store.vectors.split_at_mut_checked(4 * n).ok_or(STORAGE)?;
    let cap = NEAR_PAIRS_PER_SPHERE * n;
    let (pairs, cells) = store.indices.split_at_mut_checked(2 * cap).ok_or(STORAGE)?;
    let storage = Storage {
        pairs: pairs.as_chunks_mut::<2>().0,
        reals: &mut *store.reals,
        field,
        cells,
    };
    let solver = Solver::new(p.viscosity, far, pos, radius, nf, storage).map_err(error)?;
    body(&mut At {
        n,
        packed: &*packed,
        solver,
        io,
    })
}

impl<'s, T: Real> At<'s, T> {
    /// The far field's packed grand mobility at this configuration.
    pub(super) fn packed(&self) -> &'s [T::M3] {
        self.packed
    }

    /// `out = M_SD f` over the `2n` forces and torques (velocities and spins out), to the
    /// solver's tolerance ([`Params::solver`]); counted in `counts`.
    pub(super) fn apply(
        &mut self,
        p: &Params<T>,
        f: &[T::V3],
        out: &mut [T::V3],
        counts: &mut Counts,
    ) -> Result<(), StepError> {
        let (n, packed) = (self.n, self.packed);
        let mut far = |x: &[T::V3], y: &mut [T::V3]| {
            packed_product::<T>(packed, n, x, y);
            Ok(())
        };
        let (tol, cap) = (p.solver.tolerance, p.solver.max_iterations);
        let r = self
            .solver
            .product(&mut far, f, out, tol, cap)
            .map_err(error)?;
        if counts.products == 0 {
            counts.pairs = u32::try_from(r.pairs).unwrap_or(u32::MAX);
        }
        counts.products += 1;
        counts.iterations = counts.iterations.saturating_add(r.iterations);
        Ok(())
    }

    /// `u = M_SD,tt f` and, where `w` is given, `w = M_SD,rt f`: torque-free spheres.
    pub(super) fn velocities(
        &mut self,
        p: &Params<T>,
        f: &[T::V3],
        u: &mut [T::V3],
        w: Option<&mut [T::V3]>,
        counts: &mut Counts,
    ) -> Result<(), StepError> {
        let fill = |fin: &mut [T::V3]| {
            fin.copy_from_slice(f);
            Ok(())
        };
        self.velocities_of(p, fill, u, w, counts)
    }

    /// [`Self::velocities`] of the forces `fill` writes (into `n` zeroed vectors).
    pub(super) fn velocities_of(
        &mut self,
        p: &Params<T>,
        fill: impl FnOnce(&mut [T::V3]) -> Result<(), StepError>,
        u: &mut [T::V3],
        w: Option<&mut [T::V3]>,
        counts: &mut Counts,
    ) -> Result<(), StepError> {
        let n = self.n;
        let io = core::mem::take(&mut self.io);
        let (fin, out) = io.split_at_mut(2 * n);
        fin[n..].fill(T::V3_ZERO);
        let done = fill(&mut fin[..n]).and_then(|()| self.apply(p, fin, out, counts));
        if done.is_ok() {
            u.copy_from_slice(&out[..n]);
            if let Some(w) = w {
                w.copy_from_slice(&out[n..]);
            }
        }
        self.io = io;
        done
    }

    /// `y = M_far x` over the `2n` vectors (the packed grand mobility).
    pub(super) fn far(&self, x: &[T::V3], y: &mut [T::V3]) {
        packed_product::<T>(self.packed, self.n, x, y);
    }

    /// `b += L z`, the near field's share of the noise ([`Solver::add_near_noise`]).
    pub(super) fn add_near_noise(
        &self,
        draw: &mut dyn FnMut(&mut [T::V3; 4]),
        b: &mut [T::V3],
    ) -> Result<(), StepError> {
        self.solver.add_near_noise(draw, b).map_err(error)
    }
}
