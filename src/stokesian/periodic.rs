//! The periodic box's part of Stokesian dynamics: its far field, the Ewald sums' grand
//! mobility with pairs at their minimum image ([`Far::periodic`]). Feature `periodic`.

use super::Far;
use crate::geometry::{Named, Place};
use crate::mobility::periodic::Ewald;
use crate::real::Real;

impl<'a, T: Real> Far<'a, T> {
    /// In the periodic box of the Ewald sums `ewald`; pairs meet at their minimum image.
    pub fn periodic(ewald: &'a Ewald<T>) -> Self {
        let named = Named {
            cell: Some(ewald.cell()),
            ..Named::FREE
        };
        Self {
            place: Place::new(named),
            sums: Some(ewald),
        }
    }
}

/// [`Far::periodic`].
impl<'a, T: Real> From<&'a Ewald<T>> for Far<'a, T> {
    fn from(ewald: &'a Ewald<T>) -> Self {
        Self::periodic(ewald)
    }
}
