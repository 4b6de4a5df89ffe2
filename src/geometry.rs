//! The geometry as a step sees it: one interface ([`Hydrodynamics`]) through which the
//! stages, the constraint metric and the front ends' mobility reach the hydrodynamics
//! of free space, a wall, or a periodic box (Ewald or PSE sums, [`sums`] with the
//! `periodic` feature). It sits above the geometries themselves (`crate::mobility`:
//! `mobility.rs` with the pair blocks of `rpy.rs` and the bands of `parallel/` for
//! free space, `mobility/wall.rs`, `mobility/periodic.rs`, `mobility/pse.rs`) and the
//! noise, below the constraint solvers and the integrators that read it.
//!
//! **Why a closed enum, not a trait the step is generic over.** The geometry is data in
//! [`Params`](crate::Params) (`wall`, `periodic`, `pse`), chosen at run time by hosts,
//! the Python package and scene files, and the step's public signature has no
//! geometry parameter: a type parameter would change that signature for every caller
//! and need a dispatch from the parameters to one monomorphised step per geometry in
//! every host (each step compiled four times). Firmware drops what it does not use by
//! the kernel's features (`wall`, `periodic`, `pse`: a variant and its code compile
//! away with its feature), as before. The `match` over the variants below is the one
//! place the choice is made.
//!
//! **What a geometry gives.** Its blocks, not its loops: a source of blocks for the
//! band loops written once in `parallel/source.rs` (`Blocks`: what a row needs of a
//! sphere, the self block, the pair block; the assembly in bands, the matrix-free
//! banded and serial products and the block at `(p, q)` read them) and, with
//! rotation, for the grand mobility and the spins of `mobility/grand.rs` (`Grand`).
//! What its parameters name is asked through [`Place`] ([`Params::place`](crate::Params::place)):
//! the checks, the workspace's sizes, the noise and the minimum images never read
//! the parameters' geometry fields by hand. Adding a geometry (a slit between two
//! walls, say) is its module under `mobility/` with those two implementations, a
//! variant and its arms here, a variant of [`Place`] (and the parameter that names
//! it), its own input checks, and its tests.

mod place;
#[cfg(feature = "periodic")]
pub mod sums;

pub use place::Place;

use core::marker::PhantomData;

use crate::error::StepError;
use crate::linalg::{MobMut, with_blocks};
use crate::mobility::{self, Hydro};
use crate::noise::reduced;
use crate::parallel::{self, Parallel};
use crate::real::Real;

/// The step's periodic sums ([`sums::BoxSums`]: Ewald, or PSE with
/// [`Params::pse`](crate::Params::pse)): `Some` in a periodic box whose images interact
/// (not with free draining), derived once by the step's checks and read by every
/// product, assembly and matrix-free metric of the step.
#[cfg(feature = "periodic")]
pub type Sums<'a, T> = Option<sums::BoxSums<'a, T>>;
/// The step's periodic sums: none without the `periodic` feature (always `None`).
#[cfg(not(feature = "periodic"))]
pub type Sums<'a, T> = Option<&'a PhantomData<T>>;

/// Whether a geometry this kernel was built with has pair blocks that are not
/// symmetric (the wall's: block `(j, i)` is the transpose of `(i, j)`), so that the
/// readers of a stored nine-scalar mobility must transpose the other triangle. Without
/// one, every such branch folds away.
pub const GENERAL_BLOCKS: bool = cfg!(feature = "wall");

/// Why PSE ([`Params::pse`](crate::Params::pse)) cannot serve a stage that needs the
/// assembled mobility.
pub(crate) const PSE_ASSEMBLED: &str = "PSE (Params::pse) where the step needs the assembled mobility \
     (without matrix_free, Cholesky noise, the Sweep or Newton solver, RattleStable): \
     PSE gives products only";

/// The hydrodynamics of the geometry a step runs in, with the level and viscosity its
/// blocks are evaluated at.
#[derive(Clone, Copy, Debug)]
pub enum Hydrodynamics<'a, T: Real> {
    /// Free space (`mobility.rs`; the bands of `parallel/`).
    Free {
        /// Hydrodynamic level.
        level: Hydro,
        /// Viscosity.
        eta: T,
    },
    /// Above a no-slip wall (`mobility/wall.rs`; feature `wall`).
    #[cfg(feature = "wall")]
    Wall {
        /// Hydrodynamic level.
        level: Hydro,
        /// Viscosity.
        eta: T,
        /// The wall's height.
        height: T,
    },
    /// In a periodic box whose images interact, with the step's sums (Ewald,
    /// `mobility/periodic.rs`, or PSE, `mobility/pse.rs`; feature `periodic`).
    #[cfg(feature = "periodic")]
    Periodic {
        /// Hydrodynamic level (what free space would use where the sums have no blocks).
        level: Hydro,
        /// Viscosity.
        eta: T,
        /// The step's sums.
        sums: sums::BoxSums<'a, T>,
    },
    /// Never built: holds the lifetime where no variant borrows (without the
    /// `periodic` feature), so that the variants need no twin without it.
    #[doc(hidden)]
    Never(core::convert::Infallible, PhantomData<&'a T>),
}

impl<'a, T: Real> Hydrodynamics<'a, T> {
    /// The geometry of a step: in the box when it has sums, above the wall at `wall`
    /// (with the kernel's `wall` feature; without it the wall's code compiles away),
    /// free space otherwise.
    #[inline(always)]
    pub fn new(level: Hydro, eta: T, wall: Option<T>, sums: Sums<'a, T>) -> Self {
        #[cfg(feature = "periodic")]
        if let Some(sums) = sums {
            return Self::Periodic { level, eta, sums };
        }
        let _ = sums; // Read above only with the `periodic` feature.
        #[cfg(feature = "wall")]
        if let Some(height) = wall {
            return Self::Wall { level, eta, height };
        }
        let _ = wall; // Read above only with the `wall` feature.
        Self::Free { level, eta }
    }

    /// The geometry of a step at `place` ([`Params::place`](crate::Params::place)) with
    /// its sums: what the stages build, so that a new geometry reaches them through
    /// [`Place`] alone.
    #[inline(always)]
    pub fn at(place: Place<T>, level: Hydro, eta: T, sums: Sums<'a, T>) -> Self {
        Self::new(level, eta, place.step_wall(), sums)
    }

    /// `mu_tt(pos)` into the packed lower triangle `mu`, on the calling thread.
    pub fn assemble_tt(
        self,
        pos: &[T::V3],
        radius: &[T],
        mu: MobMut<'_, T>,
    ) -> Result<(), StepError> {
        match self {
            Self::Free { level, eta } => {
                with_blocks!(mut mu, a => mobility::assemble_tt(level, eta, pos, radius, a))
                    .map_err(StepError::from)
            }
            #[cfg(feature = "wall")]
            Self::Wall { level, eta, height } => {
                let (serial, mu) = (&parallel::Serial, mu.general());
                Ok(mobility::wall::assemble(
                    serial, level, eta, height, pos, radius, mu,
                )?)
            }
            #[cfg(feature = "periodic")]
            Self::Periodic { eta, sums, .. } => {
                // PSE has no blocks; the checks refuse it wherever the step assembles.
                let e = sums.ewald().ok_or(StepError::Unsupported(PSE_ASSEMBLED))?;
                let serial = &parallel::Serial;
                use mobility::periodic::assemble;
                Ok(with_blocks!(mut mu, mu => assemble(serial, e, eta, pos, radius, mu))?)
            }
            Self::Never(never, _) => match never {},
        }
    }

    /// `u = mu_tt(pos) f` assembled into `mu` and applied, in bands through `par`
    /// (`bands` holds their partial sums, [`crate::parallel`]).
    #[allow(clippy::too_many_arguments)]
    pub fn assemble_apply(
        self,
        par: &dyn Parallel,
        pos: &[T::V3],
        radius: &[T],
        mu: MobMut<'_, T>,
        f: &[T::V3],
        u: &mut [T::V3],
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        match self {
            Self::Free { level, eta } => with_blocks!(mut mu, a => {
                parallel::assemble_apply(par, level, eta, pos, radius, a, f, u, bands)
            })
            .map_err(StepError::from),
            #[cfg(feature = "wall")]
            Self::Wall { level, eta, height } => {
                // Assembled, then applied.
                let mu = mu.general();
                mobility::wall::assemble(par, level, eta, height, pos, radius, mu)?;
                parallel::product::<T>(par, mu, pos.len(), f, u, bands);
                Ok(())
            }
            #[cfg(feature = "periodic")]
            Self::Periodic { eta, sums, .. } => {
                let e = sums.ewald().ok_or(StepError::Unsupported(PSE_ASSEMBLED))?;
                let work = (par, bands);
                mobility::periodic::assemble_apply(e, eta, (pos, radius), mu, (f, u), work, None)
                    .map_err(StepError::from)
            }
            Self::Never(never, _) => match never {},
        }
    }

    /// [`Hydrodynamics::assemble_apply`] that also writes each row of the compact copy
    /// `copy` of `mu` ([`Params::compact_products`](crate::Params::compact_products),
    /// `noise::reduced`) in the same pass, while the row's blocks are in cache; the
    /// product reads the full blocks, with the same bits. Apart, so that a kernel whose
    /// steps keep no copy (an `f32` firmware) links none of it. Only symmetric blocks
    /// have a copy: above a wall it is refused.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble_apply_copy(
        self,
        par: &dyn Parallel,
        pos: &[T::V3],
        radius: &[T],
        mu: MobMut<'_, T>,
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
        copy: &mut [T::M3],
    ) -> Result<(), StepError> {
        match self {
            Self::Free { level, eta } => with_blocks!(mut mu, a => {
                let side = (copy, reduced::copy_start as fn(usize) -> usize);
                let (pairs, pack) = ((level, eta, pos, radius), reduced::pack_rows::<T, _>);
                parallel::assemble_apply_then(par, pairs, a, f, u, bands, side, pack)
            })
            .map_err(StepError::from),
            #[cfg(feature = "wall")]
            Self::Wall { .. } => Err(StepError::Unsupported(
                "the compact copy above a wall (its blocks are not symmetric)",
            )),
            #[cfg(feature = "periodic")]
            Self::Periodic { eta, sums, .. } => {
                let e = sums.ewald().ok_or(StepError::Unsupported(PSE_ASSEMBLED))?;
                let (work, copy) = ((par, bands), Some(copy));
                mobility::periodic::assemble_apply(e, eta, (pos, radius), mu, (f, u), work, copy)
                    .map_err(StepError::from)
            }
            Self::Never(never, _) => match never {},
        }
    }

    /// `u = mu_tt(pos) f` matrix-free: every pair block evaluated where it is used. In
    /// free space and above a wall in the bands of the stored product through `par`
    /// (`bands`: their scratch), with its bits; in the box by its sums.
    #[allow(clippy::too_many_arguments)]
    pub fn product(
        self,
        par: &dyn Parallel,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        u: &mut [T::V3],
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        match self {
            Self::Free { level, eta } => Ok(parallel::free_product::<T>(
                par, level, eta, pos, radius, f, u, bands,
            )?),
            #[cfg(feature = "wall")]
            Self::Wall { level, eta, height } => Ok(mobility::wall::free_product(
                par, level, eta, height, pos, radius, f, u, bands,
            )?),
            #[cfg(feature = "periodic")]
            Self::Periodic { eta, sums, .. } => sums.product(eta, pos, radius, f, u, (par, bands)),
            Self::Never(never, _) => match never {},
        }
    }

    /// The grand mobility (`2n x 2n` blocks, translations then rotations, packed as
    /// [`mobility::assemble_grand`] stores it) into `out`.
    pub fn assemble_grand(
        self,
        pos: &[T::V3],
        radius: &[T],
        out: &mut [T::M3],
    ) -> Result<(), StepError> {
        match self {
            Self::Free { level, eta } => mobility::assemble_grand(level, eta, pos, radius, out)?,
            #[cfg(feature = "wall")]
            Self::Wall { level, eta, height } => {
                mobility::wall::assemble_grand(level, eta, height, pos, radius, out)?
            }
            #[cfg(feature = "periodic")]
            Self::Periodic { eta, sums, .. } => {
                let Some(e) = sums.ewald() else {
                    return Err(StepError::Unsupported(
                        "PSE with rotation (its rt and rr products are not built: Ewald sums them)",
                    ));
                };
                mobility::periodic::assemble_grand(e, eta, pos, radius, out)?
            }
            Self::Never(never, _) => match never {},
        }
        Ok(())
    }

    /// `out_i += sum_j rt_ij f_j`: the spins of torque-free spheres from the forces `f`
    /// they exert on the fluid (none with free draining in free space).
    pub fn add_spin(
        self,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let (level, eta) = match self {
            Self::Free { level, eta } => (level, eta),
            #[cfg(feature = "wall")]
            Self::Wall { level, eta, height } => {
                return Ok(mobility::wall::add_spin(
                    level, eta, height, pos, radius, f, out,
                )?);
            }
            #[cfg(feature = "periodic")]
            Self::Periodic { level, eta, sums } => match sums.ewald() {
                Some(e) => return Ok(mobility::periodic::add_spin(e, eta, pos, radius, f, out)?),
                // PSE has no rt blocks (the checks refuse it with rotation).
                None => (level, eta),
            },
            Self::Never(never, _) => match never {},
        };
        if level == Hydro::FreeDraining {
            return Ok(());
        }
        let src = parallel::Pairs::new(level, eta, pos, radius);
        Ok(mobility::add_spin_of(&src, pos.len(), f, out)?)
    }

    /// The block of `mu_tt` a row-`p` entry of the matrix-free metric reads against
    /// sphere `q` (`None` for nested spheres, and always in a PSE box, which has no
    /// blocks: [`Hydrodynamics::has_blocks`]).
    #[inline(always)]
    pub fn block_at(self, pos: &[T::V3], radius: &[T], p: usize, q: usize) -> Option<T::M3> {
        match self {
            Self::Free { level, eta } => mobility::tt_block_at(level, eta, pos, radius, p, q),
            // The block (q, p), as `sym_block` reads a stored wall mobility.
            #[cfg(feature = "wall")]
            Self::Wall { level, eta, height } => {
                mobility::wall::tt_block_at(level, eta, height, pos, radius, q, p).ok()
            }
            #[cfg(feature = "periodic")]
            Self::Periodic { eta, sums, .. } => {
                mobility::periodic::tt_block_at(sums.ewald()?, eta, pos, radius, p, q)
            }
            Self::Never(never, _) => match never {},
        }
    }

    /// Whether the geometry has pair blocks to read (not PSE, which gives products only).
    #[inline(always)]
    pub fn has_blocks(self) -> bool {
        match self {
            #[cfg(feature = "periodic")]
            Self::Periodic { sums, .. } => sums.ewald().is_some(),
            _ => true,
        }
    }

    /// Whether every block is symmetric (all but the wall's), so that a table of the
    /// metric reads lower triangles only.
    #[inline(always)]
    pub fn symmetric(self) -> bool {
        match self {
            #[cfg(feature = "wall")]
            Self::Wall { .. } => false,
            _ => true,
        }
    }

    /// Whether the metric may read only the lower triangles of its blocks because they
    /// are known symmetric in bits without reading them (the Ewald box's). Free space's
    /// are too, but its entries read all nine, as they always have: the same bits.
    #[inline(always)]
    pub fn lower_only(self) -> bool {
        match self {
            #[cfg(feature = "periodic")]
            Self::Periodic { .. } => true,
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{sym_matvec, tri};
    use glam::DVec3;

    const N: usize = 7;

    /// Spheres of unequal radii, some overlapping, all above a wall at -0.5.
    fn spheres() -> ([DVec3; N], [f64; N], [DVec3; N]) {
        let pos = core::array::from_fn(|k| {
            let t = k as f64;
            DVec3::new(
                1.7 * libm::sin(1.3 * t),
                1.9 * libm::cos(0.7 * t),
                2.0 + 1.1 * t,
            )
        });
        let radius = core::array::from_fn(|k| 0.6 + 0.1 * (k % 3) as f64);
        let f = core::array::from_fn(|k| DVec3::new(libm::sin(k as f64), -0.4, 0.3 * k as f64));
        (pos, radius, f)
    }

    /// The interface's matrix-free product has the bits of its own assembly applied
    /// (the product of the stored blocks), and its metric blocks are the stored ones:
    /// in free space and above a wall, the geometries whose products promise both.
    #[test]
    fn product_and_blocks_agree_with_the_assembly() -> Result<(), StepError> {
        let (pos, radius, f) = spheres();
        let geometries = [
            Hydrodynamics::new(Hydro::Rpy, 0.9, None, None),
            Hydrodynamics::new(Hydro::Oseen, 0.9, None, None),
            #[cfg(feature = "wall")]
            Hydrodynamics::new(Hydro::Rpy, 0.9, Some(-0.5), None),
        ];
        for h in geometries {
            let mut mu = [glam::DMat3::ZERO; tri(N)];
            h.assemble_tt(&pos, &radius, MobMut::Full(&mut mu))?;
            let (mut stored, mut free) = ([DVec3::ZERO; N], [DVec3::ZERO; N]);
            sym_matvec::<f64>(&mu, N, &f, &mut stored);
            h.product(&parallel::Serial, &pos, &radius, &f, &mut free, &mut [])?;
            let bits = |v: &DVec3| v.to_array().map(f64::to_bits);
            assert!(
                free.iter().zip(&stored).all(|(a, b)| bits(a) == bits(b)),
                "{h:?}"
            );
            // Row `j` of the metric reads the block stored at `(i, j)`, `j < i`.
            for i in 0..N {
                for j in 0..i {
                    assert_eq!(
                        h.block_at(&pos, &radius, j, i),
                        Some(mu[tri(i) + j]),
                        "{h:?}"
                    );
                }
            }
        }
        Ok(())
    }

    /// The one choice: the box's sums over the wall over free space, and the wall only
    /// with its feature.
    #[test]
    fn the_geometry_is_chosen_in_one_place() {
        let free = Hydrodynamics::new(Hydro::Rpy, 1.0, None, None);
        assert!(matches!(free, Hydrodynamics::Free { .. }));
        let wall = Hydrodynamics::<f64>::new(Hydro::Rpy, 1.0, Some(0.0), None);
        assert_eq!(
            matches!(wall, Hydrodynamics::Free { .. }),
            !cfg!(feature = "wall")
        );
    }
}
