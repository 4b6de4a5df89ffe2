//! Between two parallel no-slip walls, a floor and a ceiling: what the parameters name
//! ([`Between`], always compiled, so that the checks see a slit the kernel was built
//! without) and the step's hydrodynamics ([`step`], `mobility/slit.rs`, feature `slit`).

#[cfg(feature = "slit")]
pub mod step;

use super::{Named, Surface, Surfaces};
use crate::cell::Periodic;
use crate::mobility::Hydro;
use crate::real::Real;

/// The parameters name a slit: the floor `z = floor` and the ceiling `z = ceiling`
/// ([`Params::slit`](crate::Params::slit)), with `clash` where a wall or a periodic box
/// is named beside it (which the checks refuse).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Between<T> {
    /// The floor's height.
    pub floor: T,
    /// The ceiling's height.
    pub ceiling: T,
    /// A wall or a box named beside the slit.
    pub clash: bool,
}

impl<T: Real> Between<T> {
    /// Where the parameters name a slit (first: a wall or a box beside it is refused,
    /// not taken for the geometry).
    #[inline(always)]
    pub const fn claims(named: Named<T>) -> Option<Self> {
        match named.slit {
            Some((floor, ceiling)) => Some(Self {
                floor,
                ceiling,
                clash: named.wall.is_some() || named.cell.is_some(),
            }),
            None => None,
        }
    }

    /// Not the one wall: the questions asked of a wall alone are not the slit's.
    #[inline(always)]
    pub const fn wall(self) -> Option<T> {
        None
    }

    /// No box.
    #[inline(always)]
    pub const fn cell(self) -> Option<Periodic<T>> {
        None
    }

    /// The floor, then the ceiling.
    #[inline(always)]
    pub const fn surfaces(self) -> Surfaces<T> {
        Surfaces::two(Surface::floor(self.floor), Surface::ceiling(self.ceiling))
    }

    /// The pair blocks are not symmetric (block `(j, i)` is the transpose of `(i, j)`).
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

    /// The walls `(floor, ceiling)` of a step: with the kernel's `slit` feature, and
    /// nothing named beside them.
    #[inline(always)]
    pub const fn step_walls(self) -> Option<(T, T)> {
        match self.clash || !cfg!(feature = "slit") {
            true => None,
            false => Some((self.floor, self.ceiling)),
        }
    }
}
