//! The geometry whose far field the near field corrects ([`Far`]): the far field's
//! grand mobility, and the separation at which a pair's near field is evaluated.

use super::SdError;
use crate::mobility::Hydro;
#[cfg(feature = "periodic")]
use crate::mobility::periodic::Ewald;
use crate::real::Real;

/// The far field the near field corrects: free space, the wall at a height, or the
/// periodic box with its Ewald sums (feature `periodic`).
#[derive(Clone, Copy, Debug)]
pub enum Far<'a, T: Real> {
    /// Free space.
    Free,
    /// Above the no-slip wall at this height.
    Wall(T),
    /// In the periodic box of these sums; pairs meet at their minimum image.
    #[cfg(feature = "periodic")]
    Box(&'a Ewald<T>),
    /// Never built: holds the lifetime without the `periodic` feature.
    #[cfg(not(feature = "periodic"))]
    #[doc(hidden)]
    Never(core::convert::Infallible, core::marker::PhantomData<&'a T>),
}

impl<T: Real> Far<'_, T> {
    /// The wall's height, where there is one.
    pub fn wall(self) -> Option<T> {
        match self {
            Self::Wall(h) => Some(h),
            _ => None,
        }
    }

    /// The separation `r_j - r_i` the pair's near field sees: the minimum image in the box.
    pub fn separation(self, pi: T::V3, pj: T::V3) -> T::V3 {
        match self {
            #[cfg(feature = "periodic")]
            Self::Box(e) => e.cell().minimum_image(pj - pi),
            _ => pj - pi,
        }
    }

    /// Whether a pair at separation `r` (a minimum image) is the only image within its
    /// length: in the box, `|r|` below half the smallest edge. Farther pairs get no
    /// near field (two images would be equally close at half an edge, and a correction
    /// that picked one would break the box's translation invariance).
    pub(super) fn unique(self, r: T::V3) -> bool {
        match self {
            #[cfg(feature = "periodic")]
            Self::Box(e) => {
                let [x, y, z] = e.cell().size();
                let h = x.min(y).min(z) * T::HALF;
                T::norm2(r) < h * h
            }
            _ => {
                let _ = r;
                true
            }
        }
    }

    /// The RPY grand mobility of the spheres, packed as `assemble_grand` stores it.
    pub fn assemble_grand(
        self,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        packed: &mut [T::M3],
    ) -> Result<(), SdError> {
        match self {
            Self::Free => crate::mobility::assemble_grand(Hydro::Rpy, eta, pos, radius, packed),
            Self::Wall(h) => return super::wall::far_grand(eta, h, pos, radius, packed),
            #[cfg(feature = "periodic")]
            Self::Box(e) => {
                return crate::mobility::periodic::assemble_grand(e, eta, pos, radius, packed)
                    .map_err(SdError::Periodic);
            }
            #[cfg(not(feature = "periodic"))]
            Self::Never(never, _) => match never {},
        }
        .map_err(SdError::Particle)
    }
}
