//! In a periodic box whose images interact, with the step's sums ([`crate::geometry::sums`]):
//! Ewald's (`mobility/periodic.rs`: blocks, assembly and products) or PSE's
//! (`mobility/pse.rs`: products only, which the checks hold to steps that need
//! nothing else). Feature `periodic`.

use crate::error::StepError;
use crate::geometry::free::Free;
use crate::geometry::{Geometry, PSE_ASSEMBLED, Place, Sums, sums::BoxSums};
use crate::linalg::{MobMut, with_blocks};
use crate::mobility::{Hydro, periodic};
use crate::parallel::{self, Parallel};
use crate::real::Real;

/// In the box of the step's sums, at a hydrodynamic level and viscosity.
#[derive(Clone, Copy, Debug)]
pub struct Periodic<'a, T: Real> {
    /// Hydrodynamic level (what free space would use where the sums have no blocks).
    pub level: Hydro,
    /// Viscosity.
    pub eta: T,
    /// The step's sums.
    pub sums: BoxSums<'a, T>,
}

impl<'a, T: Real> Periodic<'a, T> {
    /// The geometry at `place` where the step has sums (its images interact).
    #[inline(always)]
    pub fn at(_: Place<T>, level: Hydro, eta: T, sums: Sums<'a, T>) -> Option<Self> {
        sums.map(|sums| Self { level, eta, sums })
    }

    /// The Ewald sums: PSE has none, and the checks refuse it wherever the step assembles.
    fn ewald(self) -> Result<&'a periodic::Ewald<T>, StepError> {
        self.sums
            .ewald()
            .ok_or(StepError::Unsupported(PSE_ASSEMBLED))
    }
}

impl<T: Real> Geometry<T> for Periodic<'_, T> {
    fn assemble_tt(self, pos: &[T::V3], radius: &[T], mu: MobMut<'_, T>) -> Result<(), StepError> {
        let (e, eta) = (self.ewald()?, self.eta);
        let serial = &parallel::Serial;
        use periodic::assemble;
        Ok(with_blocks!(mut mu, mu => assemble(serial, e, eta, pos, radius, mu))?)
    }

    fn assemble_apply(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        mu: MobMut<'_, T>,
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        let (e, eta) = (self.ewald()?, self.eta);
        let work = (par, bands);
        periodic::assemble_apply(e, eta, (pos, radius), mu, (f, u), work, None)
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
        let (e, eta) = (self.ewald()?, self.eta);
        let (work, copy) = ((par, bands), Some(copy));
        periodic::assemble_apply(e, eta, (pos, radius), mu, (f, u), work, copy)
            .map_err(StepError::from)
    }

    fn product(
        self,
        par: &dyn Parallel,
        (pos, radius): (&[T::V3], &[T]),
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        self.sums.product(self.eta, pos, radius, f, u, (par, bands))
    }

    fn assemble_grand(
        self,
        pos: &[T::V3],
        radius: &[T],
        out: &mut [T::M3],
    ) -> Result<(), StepError> {
        let Some(e) = self.sums.ewald() else {
            return Err(StepError::Unsupported(
                "PSE with rotation (its rt and rr products are not built: Ewald sums them)",
            ));
        };
        Ok(periodic::assemble_grand(e, self.eta, pos, radius, out)?)
    }

    fn add_spin(
        self,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let Self { level, eta, sums } = self;
        match sums.ewald() {
            Some(e) => Ok(periodic::add_spin(e, eta, pos, radius, f, out)?),
            // PSE has no rt blocks (the checks refuse it with rotation): free space's.
            None => Free { level, eta }.add_spin(pos, radius, f, out),
        }
    }

    #[inline(always)]
    fn block_at(self, pos: &[T::V3], radius: &[T], p: usize, q: usize) -> Option<T::M3> {
        periodic::tt_block_at(self.sums.ewald()?, self.eta, pos, radius, p, q)
    }

    #[inline(always)]
    fn has_blocks(self) -> bool {
        self.sums.ewald().is_some()
    }

    #[inline(always)]
    fn lower_only(self) -> bool {
        true
    }
}
