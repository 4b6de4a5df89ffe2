//! Above a no-slip wall (`mobility/wall.rs`, feature `wall`): general (not symmetric)
//! pair blocks, assembled then applied; no compact copy.

use crate::error::StepError;
use crate::geometry::{Geometry, Place, Sums};
use crate::linalg::MobMut;
use crate::mobility::{Hydro, wall};
use crate::parallel::{self, Parallel};
use crate::real::Real;

/// Above the wall at `height`, at a hydrodynamic level and viscosity.
#[derive(Clone, Copy, Debug)]
pub struct Wall<T: Real> {
    /// Hydrodynamic level.
    pub level: Hydro,
    /// Viscosity.
    pub eta: T,
    /// The wall's height.
    pub height: T,
}

impl<T: Real> Wall<T> {
    /// The geometry at `place` where it names a wall and the kernel has its `wall`
    /// feature (the checks refuse the wall without it).
    #[inline(always)]
    pub fn at(place: Place<T>, level: Hydro, eta: T, _: Sums<'_, T>) -> Option<Self> {
        let height = place.step_wall()?;
        Some(Self { level, eta, height })
    }
}

impl<T: Real> Geometry<T> for Wall<T> {
    fn assemble_tt(self, pos: &[T::V3], radius: &[T], mu: MobMut<'_, T>) -> Result<(), StepError> {
        let Self { level, eta, height } = self;
        let (serial, mu) = (&parallel::Serial, mu.general());
        Ok(wall::assemble(serial, level, eta, height, pos, radius, mu)?)
    }

    fn assemble_apply(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        mu: MobMut<'_, T>,
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        let Self { level, eta, height } = self;
        // Assembled, then applied.
        let mu = mu.general();
        wall::assemble(par, level, eta, height, pos, radius, mu)?;
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
            "the compact copy above a wall (its blocks are not symmetric)",
        ))
    }

    fn product(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        let Self { level, eta, height } = self;
        Ok(wall::free_product(
            par, level, eta, height, pos, radius, f, u, bands,
        )?)
    }

    fn assemble_grand(
        self,
        pos: &[T::V3],
        radius: &[T],
        out: &mut [T::M3],
    ) -> Result<(), StepError> {
        let Self { level, eta, height } = self;
        Ok(wall::assemble_grand(level, eta, height, pos, radius, out)?)
    }

    fn add_spin(
        self,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let Self { level, eta, height } = self;
        Ok(wall::add_spin(level, eta, height, pos, radius, f, out)?)
    }

    /// The block (q, p), as `sym_block` reads a stored wall mobility.
    #[inline(always)]
    fn block_at(self, pos: &[T::V3], radius: &[T], p: usize, q: usize) -> Option<T::M3> {
        let Self { level, eta, height } = self;
        wall::tt_block_at(level, eta, height, pos, radius, q, p).ok()
    }

    #[inline(always)]
    fn symmetric(self) -> bool {
        false
    }
}
