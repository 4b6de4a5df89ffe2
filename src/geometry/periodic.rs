//! In a periodic box: what the parameters name ([`InBox`], always compiled, so that the
//! checks see a box the kernel was built without) and the step's hydrodynamics where its
//! images interact ([`step`], Ewald or PSE sums, feature `periodic`), what a step holds
//! for its sums (`held.rs`), and the box's and PSE's errors as the step's own.

#[cfg(feature = "periodic")]
pub(crate) mod held;
#[cfg(feature = "periodic")]
pub mod step;

use super::{Named, Surface, Surfaces};
use crate::cell::{Periodic, PeriodicError};
use crate::error::{ParticleError, StepError};
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

    /// None but the wall asked for beside the box (which the checks refuse).
    #[inline(always)]
    pub const fn surfaces(self) -> Surfaces<T> {
        match self.wall {
            Some(h) => Surfaces::one(Surface::floor(h)),
            None => Surfaces::NONE,
        }
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

/// A box or Ewald parameter the step cannot use: typed as the step's own errors (a
/// radius or particle as [`StepError::Particle`], a parameter as
/// [`StepError::BadParameter`], a box beyond the sums' bounds as
/// [`StepError::Unsupported`]), so that no new variant reaches callers' matches.
impl From<PeriodicError> for StepError {
    fn from(e: PeriodicError) -> Self {
        use PeriodicError as E;
        match e {
            E::BadEdge { .. } => Self::BadParameter("periodic (every edge finite and > 0)"),
            E::BadParameter(name) => Self::BadParameter(name),
            E::SphereTooLarge => {
                Self::BadParameter("periodic (every radius below half the smallest edge)")
            }
            E::TooElongated => Self::Unsupported(
                "a periodic box too elongated for the Ewald sums (mobility::periodic::MAX_INDEX)",
            ),
            E::Radius { particle } => Self::Particle(ParticleError::BadRadius { particle }),
            E::Particle(e) => Self::Particle(e),
        }
    }
}

/// A PSE product's error as the step's own (`mobility::pse::PseError`): the
/// box and particles as the Ewald path's, the rest named.
#[cfg(feature = "pse")]
impl From<crate::mobility::pse::PseError> for StepError {
    fn from(e: crate::mobility::pse::PseError) -> Self {
        use crate::mobility::pse::PseError as E;
        match e {
            E::Periodic(e) => e.into(),
            E::GridTooLarge => Self::Unsupported(
                "a PSE tolerance whose grid exceeds the bounds (mobility::pse::MAX_GRID, MAX_SUPPORT)",
            ),
            E::Length => Self::BadParameter("PSE: positions, radii and forces differ in length"),
            E::LargeSphere => Self::Unsupported(
                "PSE with a sphere's radius at least a third of the box's smallest edge (mobility::pse::MAX_RADIUS_FRACTION): it misses its tolerance there",
            ),
            E::Precision { .. } => Self::BadParameter(
                "a PSE tolerance below what the precision can reach (mobility::pse::min_tolerance)",
            ),
            E::Lanczos(e) => e.into(),
            E::Storage { .. } => Self::BadParameter(
                "the workspace's PSE storage (Workspace::with_pse, at least integrate::pse_storage)",
            ),
        }
    }
}
