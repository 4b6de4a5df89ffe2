//! One configuration of the iterative near field: the far field made ready and the close
//! pairs found and factored once, then every product the step needs there (the
//! velocities, and in a Brownian step the noise's solve and the far field's products its
//! Lanczos root takes).
//!
//! **The far field** ([`FarField`], chosen in [`far_field`], the one place a far field is
//! picked): the grand mobility assembled into the store's packed blocks (`tri(2n)`,
//! Ewald's sums in a box, the wall's images above it, free space's RPY), or, with the
//! fast product ([`Params::pse`]: free space's fast product, or PSE's in a box), its
//! matrix-free grand product (`FastProduct::grand`, `O(n log n)` a product, no `tri(2n)`
//! storage).

use super::{Counts, STORAGE, Store, error, tri2};
use crate::constraints::Metric;
use crate::error::StepError;
#[cfg(feature = "pse")]
use crate::geometry::fast::FastProduct;
use crate::linalg::{Mob, tri};
use crate::parallel::Parallel;
use crate::params::{NEAR_PAIRS_PER_SPHERE, Params};
use crate::real::Real;
use crate::stokesian::SdError;
use crate::stokesian::iterative::{Solver, Storage, packed_product};

use super::super::Sums;

/// The far field the near field's products read at one configuration.
#[derive(Clone, Copy)]
pub(super) enum FarField<'s, T: Real> {
    /// The packed grand mobility assembled at the configuration (`tri(2n)` blocks).
    Packed(&'s [T::M3]),
    /// A matrix-free grand product at the configuration's spheres (viscosity `eta`).
    #[cfg(feature = "pse")]
    Product {
        /// The step's fast product.
        fast: &'s dyn FastProduct<T>,
        /// Where it is taken: centres and radii.
        spheres: (&'s [T::V3], &'s [T]),
        /// The viscosity.
        eta: T,
    },
}

impl<T: Real> FarField<'_, T> {
    /// `y = M_far x` over the `2n` forces and torques (velocities and spins out).
    fn apply(self, n: usize, x: &[T::V3], y: &mut [T::V3]) -> Result<(), SdError> {
        match self {
            Self::Packed(packed) => {
                packed_product::<T>(packed, n, x, y);
                Ok(())
            }
            #[cfg(feature = "pse")]
            Self::Product { fast, spheres, eta } => {
                fast.grand(eta, spheres, x, y).map_err(SdError::Far)
            }
        }
    }
}

/// The near field's products at one configuration ([`at`]).
pub(super) struct At<'s, T: Real> {
    n: usize,
    far: FarField<'s, T>,
    solver: Solver<'s, T>,
    /// The store's `2n` forces and torques, then `2n` velocities and spins.
    io: &'s mut [T::V3],
}

/// The far field at `(pos, radius)` ([`FarField`]): the step's fast product's grand
/// product where the step has one (free space's, or PSE's in a box), else the grand
/// mobility assembled into the store's packed blocks.
fn far_field<'s, T: Real>(
    p: &Params<T>,
    ew: Sums<'s, T>,
    (pos, radius): (&'s [T::V3], &'s [T]),
    packed: &'s mut [T::M3],
) -> Result<FarField<'s, T>, StepError> {
    #[cfg(feature = "pse")]
    if let Some(fast) = ew.and_then(|s| s.pse()) {
        let spheres = (pos, radius);
        let eta = p.viscosity;
        return Ok(FarField::Product { fast, spheres, eta });
    }
    let far = super::super::near::far(p, ew)?;
    let packed = packed.get_mut(..tri2(pos.len())).ok_or(STORAGE)?;
    far.assemble_grand(p.viscosity, pos, radius, packed)
        .map_err(error)?;
    Ok(FarField::Packed(packed))
}

/// Runs `body` with the products at `(pos, radius)`: the far field made ready
/// ([`far_field`]), the close pairs factored into the store's reals.
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
    let far = far_field(p, ew, (pos, radius), &mut *store.packed)?;
    let (io, field) = store.vectors.split_at_mut_checked(4 * n).ok_or(STORAGE)?;
    let cap = NEAR_PAIRS_PER_SPHERE * n;
    let (pairs, cells) = store.indices.split_at_mut_checked(2 * cap).ok_or(STORAGE)?;
    let storage = Storage {
        pairs: pairs.as_chunks_mut::<2>().0,
        reals: &mut *store.reals,
        field,
        cells,
    };
    let geometry = super::super::near::far(p, ew)?;
    let solver = Solver::new(p.viscosity, geometry, pos, radius, nf, storage).map_err(error)?;
    body(&mut At { n, far, solver, io })
}

impl<'s, T: Real> At<'s, T> {
    /// The far field at this configuration.
    pub(super) fn far_field(&self) -> FarField<'s, T> {
        self.far
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
        let (n, field) = (self.n, self.far);
        let mut far = |x: &[T::V3], y: &mut [T::V3]| field.apply(n, x, y);
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

    /// `y = M_far x` over the `2n` vectors ([`FarField`]).
    pub(super) fn far(&self, x: &[T::V3], y: &mut [T::V3]) -> Result<(), StepError> {
        self.far.apply(self.n, x, y).map_err(error)
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

/// The constraint solve's entries (its band preconditioner, its curvature bound) from
/// the far field's `mu_tt` at `spheres`: the packed grand mobility's first `n` block rows,
/// or, where the far field is a product, each pair block evaluated where it is read (free
/// space's RPY blocks, which the fast product approximates; in PSE's box they miss the
/// images, which slows the solve and leaves where it ends: its moves are `M_SD`'s).
pub(super) fn far_metric<'a, T: Real>(
    far: FarField<'a, T>,
    spheres: (&'a [T::V3], &'a [T]),
    (grad, scale): (&'a [T::V3], T),
    par: &'a dyn Parallel,
) -> Metric<'a, T> {
    match far {
        FarField::Packed(packed) => Metric::Mobility {
            mu: Mob::Full(&packed[..tri(spheres.0.len())]),
            grad,
            scale,
            par,
            compact: None,
        },
        #[cfg(feature = "pse")]
        FarField::Product { eta, .. } => Metric::Free {
            hydro: crate::geometry::Hydrodynamics::free_space(crate::mobility::Hydro::Rpy, eta),
            pos: spheres.0,
            radius: spheres.1,
            grad,
            scale,
            par,
        },
    }
}
