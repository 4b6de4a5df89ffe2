//! In a periodic box: what the parameters name ([`InBox`], always compiled, so that the
//! checks see a box the kernel was built without) and the step's hydrodynamics where its
//! images interact ([`step`], Ewald or PSE sums, feature `periodic`).

#[cfg(feature = "periodic")]
pub mod step;

use super::Named;
use crate::cell::Periodic;
use crate::mobility::Hydro;
use crate::real::Real;

/// The parameters name a periodic box (with a wall also asked for, which the checks
/// refuse, at `wall`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InBox<T: Real> {
    /// The box.
    pub cell: Periodic<T>,
    /// A wall asked for beside the box.
    pub wall: Option<T>,
    /// Summed by PSE ([`Params::pse`](crate::Params::pse): products only, nothing
    /// stored), not by Ewald.
    pub pse: bool,
}

impl<T: Real> InBox<T> {
    /// Where the parameters name a box, with or without a wall: the box first, as every
    /// check takes it.
    #[inline(always)]
    pub const fn claims(named: Named<T>) -> Option<Self> {
        match named.cell {
            Some(cell) => Some(Self {
                cell,
                wall: named.wall,
                pse: named.pse,
            }),
            None => None,
        }
    }

    /// The wall asked for beside the box.
    #[inline(always)]
    pub const fn wall(self) -> Option<T> {
        self.wall
    }

    /// The box.
    #[inline(always)]
    pub const fn cell(self) -> Option<Periodic<T>> {
        Some(self.cell)
    }

    /// The Ewald blocks are symmetric in bits (not with a wall beside the box).
    #[inline(always)]
    pub const fn symmetric(self) -> bool {
        self.wall.is_none()
    }

    /// Symmetric blocks are stored by Ewald, not by PSE, which stores nothing.
    #[inline(always)]
    pub const fn stores_symmetric(self) -> bool {
        self.symmetric() && !self.pse
    }

    /// The stored mobility is free space's only where the images do not interact (free
    /// draining: self blocks only, the same in a box as outside it).
    #[inline(always)]
    pub const fn free_blocks(self, level: Hydro) -> bool {
        self.symmetric() && matches!(level, Hydro::FreeDraining)
    }
}
