//! Free space: the pair blocks of `rpy.rs` through `mobility.rs`, in the bands of
//! `parallel/` (the band loops of `parallel/source.rs` and `mobility/grand.rs`); and
//! the fast free-space product's steps (`free/fast.rs`, feature `fast-free`).

#[cfg(feature = "fast-free")]
pub(crate) mod fast;

use super::{Geometry, Surfaces};
use crate::cell::Periodic;
use crate::error::StepError;
use crate::linalg::{MobMut, with_blocks};
use crate::mobility::{self, Hydro};
use crate::noise::reduced;
use crate::parallel::{self, Parallel};
use crate::real::Real;

/// Free space at a hydrodynamic level and viscosity.
#[derive(Clone, Copy, Debug)]
pub struct Free<T: Real> {
    /// Hydrodynamic level.
    pub level: Hydro,
    /// Viscosity.
    pub eta: T,
}

impl<T: Real> Free<T> {
    /// Free space: where a step runs when no other geometry claims its place (the
    /// registration's fallback).
    #[inline(always)]
    pub const fn new(level: Hydro, eta: T) -> Self {
        Self { level, eta }
    }
}

/// The parameters name no other geometry: free space, the registration's fallback.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Anywhere;

impl Anywhere {
    /// Free space, where no other geometry claims the parameters.
    #[inline(always)]
    pub const fn new() -> Self {
        Self
    }

    /// No wall.
    #[inline(always)]
    pub const fn wall<T: Real>(self) -> Option<T> {
        None
    }

    /// No box.
    #[inline(always)]
    pub const fn cell<T: Real>(self) -> Option<Periodic<T>> {
        None
    }

    /// No hard surface.
    #[inline(always)]
    pub const fn surfaces<T: Real>(self) -> Surfaces<T> {
        Surfaces::NONE
    }

    /// Free space's blocks are symmetric in bits.
    #[inline(always)]
    pub const fn symmetric(self) -> bool {
        true
    }

    /// A step stores them as such.
    #[inline(always)]
    pub const fn stores_symmetric(self) -> bool {
        true
    }

    /// The stored mobility is free space's.
    #[inline(always)]
    pub const fn free_blocks(self, _: Hydro) -> bool {
        true
    }
}

impl<T: Real> Geometry<T> for Free<T> {
    fn assemble_tt(self, pos: &[T::V3], radius: &[T], mu: MobMut<'_, T>) -> Result<(), StepError> {
        let Self { level, eta } = self;
        with_blocks!(mut mu, a => mobility::assemble_tt(level, eta, pos, radius, a))
            .map_err(StepError::from)
    }

    fn assemble_apply(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        mu: MobMut<'_, T>,
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        let Self { level, eta } = self;
        with_blocks!(mut mu, a => {
            parallel::assemble_apply(par, level, eta, pos, radius, a, f, u, bands)
        })
        .map_err(StepError::from)
    }

    fn assemble_apply_copy(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        mu: MobMut<'_, T>,
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
        copy: &mut [T::M3],
    ) -> Result<(), StepError> {
        let Self { level, eta } = self;
        with_blocks!(mut mu, a => {
            let side = (copy, reduced::copy_start as fn(usize) -> usize);
            let (pairs, pack) = ((level, eta, pos, radius), reduced::pack_rows::<T, _>);
            parallel::assemble_apply_then(par, pairs, a, f, u, bands, side, pack)
        })
        .map_err(StepError::from)
    }

    fn product(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        let Self { level, eta } = self;
        Ok(parallel::free_product::<T>(
            par, level, eta, pos, radius, f, u, bands,
        )?)
    }

    fn assemble_grand(
        self,
        pos: &[T::V3],
        radius: &[T],
        out: &mut [T::M3],
    ) -> Result<(), StepError> {
        Ok(mobility::assemble_grand(
            self.level, self.eta, pos, radius, out,
        )?)
    }

    fn add_spin(
        self,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let Self { level, eta } = self;
        if level == Hydro::FreeDraining {
            return Ok(());
        }
        let src = parallel::Pairs::new(level, eta, pos, radius);
        Ok(mobility::add_spin_of(&src, pos.len(), f, out)?)
    }

    #[inline(always)]
    fn block_at(self, pos: &[T::V3], radius: &[T], p: usize, q: usize) -> Option<T::M3> {
        mobility::tt_block_at(self.level, self.eta, pos, radius, p, q)
    }
}
