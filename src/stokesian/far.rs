//! The geometry whose far field the near field corrects ([`Far`]): the far field's
//! grand mobility, and the separation at which a pair's near field is evaluated.
//!
//! A far field is a geometry's place and sums ([`crate::geometry::Place`],
//! [`crate::geometry::BlockSums`]: those with blocks, `Send` and `Sync`), the same a
//! step runs in: its grand mobility is the
//! geometry's own ([`Geometry::assemble_grand`](crate::geometry::Geometry), through the
//! registration's [`Hydrodynamics`] at the RPY level), its minimum images the place's
//! box. Nothing here names a geometry: a geometry's constructor of its far field (the
//! box's [`Far::periodic`]) and its sphere corrections (the wall's) live in its own
//! file under `stokesian/`.

use super::SdError;
use crate::cell::Periodic;
use crate::error::StepError;
use crate::geometry::{BlockSums, Hydrodynamics, Named, Place, Sums};
use crate::mobility::Hydro;
use crate::real::Real;

/// The far field the near field corrects: free space ([`Far::FREE`]), the no-slip wall
/// at a height ([`Far::above`]), the periodic box of an Ewald sum ([`Far::periodic`],
/// feature `periodic`; `From<&Ewald>`), or the geometry of a step ([`Far::at`]).
#[derive(Clone, Copy, Debug)]
pub struct Far<'a, T: Real> {
    /// Where the spheres are.
    pub(super) place: Place<T>,
    /// The place's sums with blocks (a box's Ewald sums): set by a geometry's own
    /// constructor (`stokesian/periodic.rs`), which names both.
    pub(super) sums: BlockSums<'a, T>,
}

impl<'a, T: Real> Far<'a, T> {
    /// Free space.
    pub const FREE: Self = Self {
        place: Place::new(Named::FREE),
        sums: None,
    };

    /// Above the no-slip wall at `height` (with the kernel's `wall` feature: without it
    /// the grand mobility refuses the wall, [`SdError::Params`]).
    pub const fn above(height: T) -> Self {
        let named = Named {
            wall: Some(height),
            ..Named::FREE
        };
        Self {
            place: Place::new(named),
            sums: None,
        }
    }

    /// The far field of a step at `place` ([`Params::place`](crate::Params::place))
    /// with its sums: `None` where the place's box has none (sums the step never
    /// derived). A box summed by PSE (products only, no blocks) is a far field without
    /// sums: the near field's pair corrections read only the box's cell, the minimum
    /// image and RPY's pair blocks, and its grand mobility is PSE's product
    /// (`integrate/near_iter/solve.rs`); [`Far::assemble_grand`] refuses it.
    pub fn at(place: Place<T>, sums: Sums<'a, T>) -> Option<Self> {
        let given = sums.is_some();
        // Without the `periodic` feature both sums are the same empty type.
        #[allow(clippy::useless_conversion)]
        let sums: BlockSums<'a, T> = sums.and_then(|s| s.try_into().ok());
        let ok = match place.summed_cell(Hydro::Rpy) {
            Some(_) => given,
            None => sums.is_none(),
        };
        ok.then_some(Self { place, sums })
    }

    /// The wall's height, where there is one.
    pub fn wall(self) -> Option<T> {
        self.place.wall()
    }

    /// The periodic box, where there is one: pairs meet at their minimum image.
    pub fn cell(self) -> Option<Periodic<T>> {
        self.place.step_cell()
    }

    /// The separation `r_j - r_i` the pair's near field sees: the minimum image in the box.
    pub fn separation(self, pi: T::V3, pj: T::V3) -> T::V3 {
        match self.cell() {
            Some(c) => c.minimum_image(pj - pi),
            None => pj - pi,
        }
    }

    /// Whether a pair at separation `r` (a minimum image) is the only image within its
    /// length: in the box, `|r|` below half the smallest edge. Farther pairs get no
    /// near field (two images would be equally close at half an edge, and a correction
    /// that picked one would break the box's translation invariance).
    pub(super) fn unique(self, r: T::V3) -> bool {
        match self.cell() {
            Some(c) => {
                let [x, y, z] = c.size();
                let h = x.min(y).min(z) * T::HALF;
                T::norm2(r) < h * h
            }
            None => true,
        }
    }

    /// The RPY grand mobility of the spheres, packed as `assemble_grand` stores it: the
    /// geometry's own. A geometry the kernel was built without, or a box without the
    /// Ewald sums' blocks (PSE's, [`Far::at`]), is refused ([`SdError::Params`]), not
    /// taken for free space.
    pub fn assemble_grand(
        self,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        packed: &mut [T::M3],
    ) -> Result<(), SdError> {
        let p = self.place;
        let unsummed = p.summed_cell(Hydro::Rpy).is_some() && self.sums.is_none();
        if p.wall() != p.step_wall() || p.cell() != p.step_cell() || unsummed {
            return Err(SdError::Params);
        }
        // Without the `periodic` feature both sums are the same empty type.
        #[allow(clippy::useless_conversion)]
        let geometry = Hydrodynamics::at(p, Hydro::Rpy, eta, self.sums.map(Into::into));
        geometry
            .assemble_grand(pos, radius, packed)
            .map_err(|e| match e {
                StepError::Particle(e) => SdError::Particle(e),
                e => SdError::Far(e),
            })
    }
}
