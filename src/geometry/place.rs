//! Where a step's spheres are, as its parameters name it ([`Place`], written by the
//! registration `geometries!`): free space, above a wall, or in a periodic box. The
//! parameter-level companion of [`Hydrodynamics`](super::Hydrodynamics): what the
//! checks, the workspace's sizes, the noise and every pair geometry (minimum images)
//! ask of the geometry before a step has its sums. Each geometry answers in its own
//! module (`free.rs`, `wall.rs`, `periodic.rs`: its variant's type); here the answers
//! are forwarded, and read by hand from [`Params`](crate::Params) nowhere
//! ([`Params::place`](crate::Params::place)).

use super::{Place, Surfaces};
use crate::cell::Periodic;
use crate::mobility::Hydro;
use crate::real::Real;

/// What a step's parameters name of its geometry, each geometry's parameter read once
/// ([`Params::place`](crate::Params::place)); [`Place::new`] asks the registered
/// geometries which of them claims it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Named<T: Real> {
    /// The wall's height ([`Params::wall`](crate::Params::wall)).
    pub wall: Option<T>,
    /// A slit's floor and ceiling ([`Params::slit`](crate::Params::slit)).
    pub slit: Option<(T, T)>,
    /// The periodic box ([`Params::periodic`](crate::Params::periodic)).
    pub cell: Option<Periodic<T>>,
    /// A box summed by PSE ([`Params::pse`](crate::Params::pse)).
    pub pse: bool,
}

impl<T: Real> Named<T> {
    /// Nothing named: free space.
    pub const FREE: Self = Self {
        wall: None,
        slit: None,
        cell: None,
        pse: false,
    };
}

impl<T: Real> Place<T> {
    /// The wall's height where a wall is asked for.
    #[inline(always)]
    pub const fn wall(self) -> Option<T> {
        each_place!(self, g => g.wall())
    }

    /// The periodic box where one is asked for.
    #[inline(always)]
    pub const fn cell(self) -> Option<Periodic<T>> {
        each_place!(self, g => g.cell())
    }

    /// The hard surfaces the spheres may not cross (the wall's plane; none in free
    /// space or in a box): what the acceptance checks, the workspace holds links for
    /// and the contacts hold.
    #[inline(always)]
    pub const fn surfaces(self) -> Surfaces<T> {
        each_place!(self, g => g.surfaces())
    }

    /// Whether the stored translational blocks are symmetric in bits, so that the
    /// mobility may be stored as six scalars a block (not above a wall).
    #[inline(always)]
    pub const fn symmetric(self) -> bool {
        each_place!(self, g => g.symmetric())
    }

    /// Whether a step stores a mobility of symmetric blocks to copy (not above a wall,
    /// nor in a box summed by PSE, which stores nothing).
    #[inline(always)]
    pub const fn stores_symmetric(self) -> bool {
        each_place!(self, g => g.stores_symmetric())
    }

    /// Whether the stored mobility at `level` is free space's (no wall, no box whose
    /// images interact): what a compact copy and the reduced noise read.
    #[inline(always)]
    pub const fn free_blocks(self, level: Hydro) -> bool {
        each_place!(self, g => g.free_blocks(level))
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
                    let place = Place::<f64>::new(Named {
                        wall,
                        slit: None,
                        cell: periodic,
                        pse,
                    });
                    assert_eq!(place.wall(), wall);
                    // The wall's plane is the one hard surface, a floor.
                    assert_eq!(place.surfaces().floor(), wall);
                    assert_eq!(place.surfaces().len(), usize::from(wall.is_some()));
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
