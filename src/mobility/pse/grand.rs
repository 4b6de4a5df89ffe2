//! PSE's grand product `(U, W) = M (F, T)`: the periodic RPY grand mobility (the
//! rotation blocks too) applied to forces and torques, with the split and sums of the
//! translation product ([`Pse::apply`]):
//!
//! * wave space: the torques spread with the forces (six complex values per grid point),
//!   one kernel for all four blocks mode by mode (`wave.rs`, the Ewald path's
//!   wave-space rotation blocks, `periodic/rot.rs`), the spins interpolated with the
//!   velocities;
//! * real space: the Ewald path's real-space blocks of all four kinds
//!   (`periodic::real_grand`, the `rr` self block), row by row (`near.rs`).
//!
//! The translation rule's parameters serve it: the rotations' errors stay below the
//! tolerance (`docs/PERIODIC.md`, section PSE), so there is no separate rule.

use super::{Pse, PseError, PseSize, PseStorage, Source, Spheres, jobs, near};
use crate::real::Real;

impl<T: Real> Pse<T> {
    /// Storage [`Pse::apply_grand`] needs for `n` spheres (it serves [`Pse::apply`]
    /// too): the grid's six components per point instead of three, and two rows per
    /// sphere.
    pub fn storage_grand(&self, n: usize) -> PseSize {
        let [mx, my, mz] = self.grid.m;
        let size = self.storage(n);
        PseSize {
            complex: size.complex + 3 * mx * my * mz,
            vectors: 2 * n,
            ..size
        }
    }

    /// `(vel, spin) = M (force, torque)`: the periodic RPY grand mobility (viscosity
    /// `eta`) of the spheres at `pos` (any image) with radii `radius` (in
    /// `(0, a_max]`) applied to the forces and torques, to the tolerance: velocities
    /// into `vel`, rotations into `spin`, overlapping pairs as the Ewald path
    /// ([`crate::mobility::periodic::assemble_grand`]). With no torque the velocities
    /// are [`Pse::apply`]'s, bit for bit. The storage at least [`Pse::storage_grand`];
    /// a [`PseStorage::with_parallel`] pool gives the bits of one thread. On error the
    /// outputs are unspecified.
    ///
    /// Called over `2n` vectors (forces then torques in, velocities then spins out),
    /// as a far-field closure takes them: `|x, y| { let (f, t) = x.split_at(n);
    /// let (u, w) = y.split_at_mut(n); pse.apply_grand(eta, (pos, radius), f, t, u, w,
    /// &mut store) }`.
    #[allow(clippy::too_many_arguments)]
    pub fn apply_grand(
        &self,
        eta: T,
        (pos, radius): (&[T::V3], &[T]),
        force: &[T::V3],
        torque: &[T::V3],
        vel: &mut [T::V3],
        spin: &mut [T::V3],
        store: &mut PseStorage<'_, T>,
    ) -> Result<(), PseError> {
        let n = pos.len();
        if spin.len() != n {
            return Err(PseError::Length);
        }
        let size = self.storage_grand(n);
        self.check(eta, (pos, radius), (force, Some(torque)), vel, size, store)?;
        let par = store.parallel;
        let (order, start) = store.index.split_at_mut(n);
        near::build(self, pos, order, start);
        let (order, start) = (&*order, &*start);
        let rows = &mut store.vectors[..2 * n];
        let sources = (force, torque);
        jobs::pieces(par, (&mut *rows, n, 2), jobs::none(), |a, r, _| {
            near::product_grand(self, eta, (pos, radius), sources, (order, start), a, r)
        })?;
        for (&i, r) in order.iter().zip(rows.chunks_exact(2)) {
            vel[i] = r[0];
            spin[i] = r[1];
        }
        let spheres = Spheres { pos, radius, order };
        let source = Source::Grand(force, torque);
        let work = (&mut *store.complex, rows, par);
        self.wave(eta, spheres, source, work, (vel, Some(spin)));
        Ok(())
    }
}
