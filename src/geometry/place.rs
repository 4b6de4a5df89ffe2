//! Where a step's spheres are, as its parameters name it ([`Place`]): free space, above
//! a wall, or in a periodic box. The parameter-level companion of
//! [`Hydrodynamics`](super::Hydrodynamics): what the checks, the workspace's sizes, the
//! noise and every pair geometry (minimum images) ask of the geometry before a step has
//! its sums, answered in one place instead of by reading
//! [`Params::wall`](crate::Params::wall) and [`Params::periodic`](crate::Params::periodic)
//! by hand ([`Params::place`](crate::Params::place)).

use crate::cell::Periodic;
use crate::mobility::Hydro;
use crate::real::Real;

/// The geometry a step's parameters name, before the kernel's features are applied
/// (what is asked: the checks refuse a geometry the kernel was built without, and a box
/// with a wall).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Place<T: Real> {
    /// Free space.
    Free,
    /// Above the no-slip wall `z = height`.
    Wall {
        /// The wall's height.
        height: T,
    },
    /// In a periodic box (with the wall also asked for, which the checks refuse, at
    /// `wall`).
    Box {
        /// The box.
        cell: Periodic<T>,
        /// A wall asked for beside the box.
        wall: Option<T>,
        /// Summed by PSE ([`Params::pse`](crate::Params::pse): products only, nothing
        /// stored), not by Ewald.
        pse: bool,
    },
}

impl<T: Real> Place<T> {
    /// The place of a wall at `wall` and a box `cell` summed by PSE where `pse` (either
    /// may be absent): the box first, as every check takes it.
    #[inline(always)]
    pub const fn new(wall: Option<T>, cell: Option<Periodic<T>>, pse: bool) -> Self {
        match (cell, wall) {
            (Some(cell), wall) => Self::Box { cell, wall, pse },
            (None, Some(height)) => Self::Wall { height },
            (None, None) => Self::Free,
        }
    }

    /// The wall's height where a wall is asked for.
    #[inline(always)]
    pub const fn wall(self) -> Option<T> {
        match self {
            Self::Wall { height } => Some(height),
            Self::Box { wall, .. } => wall,
            Self::Free => None,
        }
    }

    /// The periodic box where one is asked for.
    #[inline(always)]
    pub const fn cell(self) -> Option<Periodic<T>> {
        match self {
            Self::Box { cell, .. } => Some(cell),
            _ => None,
        }
    }

    /// The wall a step runs above: with the kernel's `wall` feature (without it the
    /// wall's code compiles away, and the checks refuse the wall).
    #[inline(always)]
    pub const fn step_wall(self) -> Option<T> {
        match self.wall() {
            Some(h) if cfg!(feature = "wall") => Some(h),
            _ => None,
        }
    }

    /// The box of a step's minimum images: with the kernel's `periodic` feature
    /// (without it the box's code compiles away, and the checks refuse the box).
    #[inline(always)]
    pub const fn step_cell(self) -> Option<Periodic<T>> {
        match self.cell() {
            Some(c) if cfg!(feature = "periodic") => Some(c),
            _ => None,
        }
    }

    /// The step's box when its images interact through the mobility at `level`: not
    /// with free draining, whose mobility has self blocks only (the same in a box as
    /// outside it).
    #[inline(always)]
    pub const fn summed_cell(self, level: Hydro) -> Option<Periodic<T>> {
        match level {
            Hydro::FreeDraining => None,
            _ => self.step_cell(),
        }
    }

    /// Whether the stored translational blocks at `level` are symmetric in bits, so
    /// that the mobility may be stored as six scalars a block: not above a wall.
    #[inline(always)]
    pub const fn symmetric(self) -> bool {
        self.wall().is_none()
    }

    /// Whether a step stores a mobility of symmetric blocks to copy: not above a wall,
    /// nor in a box summed by PSE, which stores nothing.
    #[inline(always)]
    pub const fn stores_symmetric(self) -> bool {
        self.symmetric() && !matches!(self, Self::Box { pse: true, .. })
    }

    /// Whether the stored mobility at `level` is free space's (no wall, no box whose
    /// images interact): what a compact copy and the reduced noise read.
    #[inline(always)]
    pub const fn free_blocks(self, level: Hydro) -> bool {
        let summed = self.cell().is_some() && !matches!(level, Hydro::FreeDraining);
        self.symmetric() && !summed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every answer is the reading of the parameters it replaces, for every combination
    /// of a wall, a box, PSE and the level (a box with a wall included, which the checks
    /// refuse but the workspace's sizes still see).
    #[test]
    fn answers_are_the_parameters_read_by_hand() -> Result<(), crate::cell::PeriodicError> {
        let cell = Periodic::new([10.0, 11.0, 12.0])?;
        for wall in [None, Some(-0.5)] {
            for periodic in [None, Some(cell)] {
                for pse in [false, true] {
                    let place = Place::<f64>::new(wall, periodic, pse);
                    assert_eq!(place.wall(), wall);
                    assert_eq!(place.cell(), periodic);
                    assert_eq!(place.symmetric(), wall.is_none());
                    let stored = wall.is_none() && !(periodic.is_some() && pse);
                    assert_eq!(place.stores_symmetric(), stored);
                    for level in [Hydro::Rpy, Hydro::Oseen, Hydro::FreeDraining] {
                        let summed = periodic.is_some() && level != Hydro::FreeDraining;
                        assert_eq!(place.free_blocks(level), wall.is_none() && !summed);
                        let step = periodic.filter(|_| cfg!(feature = "periodic"));
                        let step = step.filter(|_| level != Hydro::FreeDraining);
                        assert_eq!(place.summed_cell(level), step);
                    }
                    let step = wall.filter(|_| cfg!(feature = "wall"));
                    assert_eq!(place.step_wall(), step);
                }
            }
        }
        Ok(())
    }
}
