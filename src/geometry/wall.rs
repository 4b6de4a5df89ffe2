//! Above a no-slip wall: what the parameters name ([`Above`], always compiled, so that
//! the checks see a wall the kernel was built without) and the step's hydrodynamics
//! ([`step`], `mobility/wall.rs`, feature `wall`).

#[cfg(feature = "wall")]
pub mod step;

use super::{Named, Surface, Surfaces};
use crate::cell::Periodic;
use crate::mobility::Hydro;
use crate::real::Real;

/// The parameters name the no-slip wall `z = height` (and no periodic box).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Above<T> {
    /// The wall's height.
    pub height: T,
}

impl<T: Real> Above<T> {
    /// Where the parameters name a wall.
    #[inline(always)]
    pub const fn claims(named: Named<T>) -> Option<Self> {
        match named.wall {
            Some(height) => Some(Self { height }),
            None => None,
        }
    }

    /// The wall's height.
    #[inline(always)]
    pub const fn wall(self) -> Option<T> {
        Some(self.height)
    }

    /// No box.
    #[inline(always)]
    pub const fn cell(self) -> Option<Periodic<T>> {
        None
    }

    /// The wall's plane, a floor: the spheres stay above it.
    #[inline(always)]
    pub const fn surfaces(self) -> Surfaces<T> {
        Surfaces::one(Surface::floor(self.height))
    }

    /// The wall's pair blocks are not symmetric (block `(j, i)` is the transpose of
    /// `(i, j)`).
    #[inline(always)]
    pub const fn symmetric(self) -> bool {
        false
    }

    /// Nothing symmetric is stored.
    #[inline(always)]
    pub const fn stores_symmetric(self) -> bool {
        false
    }

    /// The stored mobility is never free space's.
    #[inline(always)]
    pub const fn free_blocks(self, _: Hydro) -> bool {
        false
    }
}
