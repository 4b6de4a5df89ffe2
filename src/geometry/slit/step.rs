//! Between two walls (`mobility/slit.rs`, feature `slit`): general (not symmetric) pair
//! blocks, assembled then applied; no compact copy.

use crate::error::StepError;
use crate::geometry::{Geometry, Place, Sums};
use crate::linalg::MobMut;
use crate::mobility::Hydro;
use crate::mobility::slit::{self, SlitError};
use crate::parallel::{self, Parallel};
use crate::real::Real;

/// Between the floor and the ceiling `walls`, at a hydrodynamic level and viscosity.
#[derive(Clone, Copy, Debug)]
pub struct Slit<T: Real> {
    /// Hydrodynamic level.
    pub level: Hydro,
    /// Viscosity.
    pub eta: T,
    /// The floor's and the ceiling's heights.
    pub walls: (T, T),
}

impl<T: Real> Slit<T> {
    /// The geometry at `place` where it names a slit and the kernel has its `slit`
    /// feature (the checks refuse the slit without it).
    #[inline(always)]
    pub fn at(place: Place<T>, level: Hydro, eta: T, _: Sums<'_, T>) -> Option<Self> {
        match place {
            Place::Slit(b) => Some(Self {
                level,
                eta,
                walls: b.step_walls()?,
            }),
            _ => None,
        }
    }

    #[inline(always)]
    fn of(self) -> slit::Walls<T> {
        (self.level, self.eta, self.walls)
    }
}

impl<T: Real> Geometry<T> for Slit<T> {
    fn assemble_tt(self, pos: &[T::V3], radius: &[T], mu: MobMut<'_, T>) -> Result<(), StepError> {
        let mu = mu.general();
        Ok(slit::assemble(
            &parallel::Serial,
            self.of(),
            pos,
            radius,
            mu,
        )?)
    }

    fn assemble_apply(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        mu: MobMut<'_, T>,
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        let mu = mu.general();
        slit::assemble(par, self.of(), pos, radius, mu)?;
        parallel::product::<T>(par, mu, pos.len(), f, u, bands);
        Ok(())
    }

    fn assemble_apply_copy(
        self,
        _: &dyn Parallel,
        _: (&[T::V3], &[T]),
        _: MobMut<'_, T>,
        _: (&[T::V3], &mut [T::V3]),
        _: &mut [T::V3],
        _: &mut [T::M3],
    ) -> Result<(), StepError> {
        Err(StepError::Unsupported(
            "the compact copy in a slit (its blocks are not symmetric)",
        ))
    }

    fn product(
        self,
        par: &dyn Parallel,
        spheres: (&[T::V3], &[T]),
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        Ok(slit::free_product(par, self.of(), spheres, f, u, bands)?)
    }

    fn assemble_grand(
        self,
        pos: &[T::V3],
        radius: &[T],
        out: &mut [T::M3],
    ) -> Result<(), StepError> {
        Ok(slit::assemble_grand(self.of(), pos, radius, out)?)
    }

    fn add_spin(
        self,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        Ok(slit::add_spin(self.of(), (pos, radius), f, out)?)
    }

    /// The block (q, p), as `sym_block` reads a stored general mobility.
    #[inline(always)]
    fn block_at(self, pos: &[T::V3], radius: &[T], p: usize, q: usize) -> Option<T::M3> {
        slit::tt_block_at(self.of(), pos, radius, q, p).ok()
    }

    #[inline(always)]
    fn symmetric(self) -> bool {
        false
    }
}

// The slit's errors as the step's own, here in the geometry layer: the mobility layer
// below does not know the step's error.
impl From<SlitError> for StepError {
    fn from(e: SlitError) -> Self {
        match e {
            SlitError::Particle(e) => e.into(),
            SlitError::NotPositive { .. } => StepError::Unsupported(
                "a sphere so near both walls of a slit that the superposition's self \
                 mobility is not positive definite (docs/GEOMETRY.md, \"The slit\")",
            ),
        }
    }
}
