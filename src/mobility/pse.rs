//! The positively split Ewald (PSE) product `u = M F` of the periodic RPY mobility
//! (Fiore, Balboa Usabiaga, Donev & Swan, J. Chem. Phys. 146, 124116, 2017), in
//! `O(N log N)`: the same split as the Ewald path ([`crate::mobility::periodic`]),
//! Hasimoto's `H(k) = (1 + k^2/(4 xi^2)) exp(-k^2/(4 xi^2))` with Beenakker's sphere
//! factors `1 - k^2 a^2 / 6`, summed differently:
//!
//! * wave space on a grid: Gaussian spreading of `F_j` and `a_j^2 F_j` (`spread.rs`), a
//!   3D FFT (`mobility/fft.rs`), the kernel mode by mode (`wave.rs`), the inverse FFT and
//!   Gaussian interpolation;
//! * real space as a sparse near-field sum with a cell list (`near.rs`), each block the
//!   Ewald path's real-space block, so the halves add to the same periodic RPY.
//!
//! The grand product `(U, W) = M (F, T)`, rotations too, is [`Pse::apply_grand`]
//! (`grand.rs`): the torques spread with the forces, the Ewald path's rotation blocks
//! in both halves.
//!
//! One tolerance sets every parameter ([`Pse::with_xi`], `docs/PERIODIC.md`, section
//! PSE). Brownian displacements of covariance `M` come from [`Pse::noise`] (`noise.rs`);
//! a host's thread pool runs the pieces ([`PseStorage::with_parallel`], `jobs.rs`) with
//! the bits of one thread. The kernel stays `no_std`, allocation-free and without
//! `unsafe`: the caller owns the grid, the cell list and the rows ([`Pse::storage`],
//! [`PseStorage`]).

mod grand;
mod jobs;
mod near;
mod noise;
mod params;
mod spread;
mod stage;
mod wave;

use core::fmt;

pub use super::fft::{Cx, good_size};
// The transform is shared with the fast free-space product; named here for the PSE
// grid's files.
use super::fft;
pub use spread::MAX_SUPPORT;

use crate::fault::ParticleError;
use crate::mobility::periodic::real::Split;
use crate::mobility::periodic::{Periodic, PeriodicError};
use crate::noise::lanczos::LanczosError;
use crate::parallel::{Parallel, Serial};
use crate::real::Real;

/// `xi a_max` of [`Pse::new`]: the cost optimum measured at volume fraction 0.1
/// (`docs/PERIODIC.md`).
pub const XI_PSE: f64 = 0.5;

/// The largest grid edge, in points (a bound on the storage a box can ask for).
pub const MAX_GRID: usize = 2048;

/// The tolerances [`Pse::with_xi`] accepts, `MIN_TOLERANCE ..= MAX_TOLERANCE`: below,
/// the Ewald path is the tool (it sums to rounding); above, the rule's asymptotic
/// error estimates no longer hold (a host checks a scene's tolerance against these).
pub const MIN_TOLERANCE: f64 = 1e-12;
/// See [`MIN_TOLERANCE`].
pub const MAX_TOLERANCE: f64 = 0.1;

/// The largest sphere PSE takes, as a fraction of the box's smallest edge (radius
/// below it): from a third of the edge on, the rule's parameters miss the tolerance
/// against the Ewald sum (measured error over tolerance, one to three spheres: at most
/// 0.26 at 0.3 of the edge, 0.90 at 0.35, 1.19 at 0.38, 2.2 at 0.42, 4.5 at 0.48;
/// `tests/kernel/pse.rs`). The Ewald path takes any sphere below half the edge.
pub const MAX_RADIUS_FRACTION: f64 = 1.0 / 3.0;

/// Machine epsilons of the precision below which no tolerance is accepted: the FFTs'
/// and sums' rounding leaves a relative error of about 4 to 7 epsilons in `f32`
/// (4e-7 to 7e-7 against the Ewald sum whatever the tolerance asked below 1e-6), so
/// `f32` takes tolerances from 1.9e-6 on; `f64`'s floor is [`MIN_TOLERANCE`].
pub const EPSILONS: f64 = 16.0;

/// The smallest tolerance PSE accepts in precision `T`: [`MIN_TOLERANCE`], or
/// [`EPSILONS`] epsilons of `T` where that is larger (`f32`).
pub fn min_tolerance<T: Real>() -> f64 {
    MIN_TOLERANCE.max(EPSILONS * T::EPSILON.to_f64())
}

/// A rejected PSE parameter, configuration or storage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PseError {
    /// The box, a parameter, a radius or a position (as the Ewald path).
    Periodic(PeriodicError),
    /// The tolerance asks for a Gaussian support above [`MAX_SUPPORT`] points or a grid
    /// edge above [`MAX_GRID`].
    GridTooLarge,
    /// Positions, radii, forces and output differ in length.
    Length,
    /// The real-space noise's Lanczos square root failed (not converged, or the near
    /// field not positive definite: `docs/PERIODIC.md`, section PSE).
    Lanczos(LanczosError),
    /// The largest radius is at least [`MAX_RADIUS_FRACTION`] of the box's smallest
    /// edge, where PSE misses its tolerance (the Ewald path is the tool there).
    LargeSphere,
    /// The tolerance is below what the precision can reach ([`min_tolerance`], the
    /// floor given).
    Precision {
        /// The smallest tolerance this precision accepts.
        floor: f64,
    },
    /// Caller storage too small (`need` and `have` per array).
    Storage {
        /// Values needed: complex values, indices and vectors ([`Pse::storage`]); for
        /// [`Pse::noise`]'s own arrays, its vectors and scalars, then 0.
        need: [usize; 3],
        /// Values given, in the same order.
        have: [usize; 3],
    },
}

impl fmt::Display for PseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Periodic(e) => write!(f, "{e}"),
            Self::GridTooLarge => write!(f, "the PSE tolerance needs too large a grid"),
            Self::Lanczos(e) => write!(f, "PSE real-space noise: {e}"),
            Self::LargeSphere => write!(
                f,
                "a sphere's radius is at least a third of the box's smallest edge, where PSE misses its tolerance: use the Ewald sum"
            ),
            Self::Precision { floor } => write!(
                f,
                "the PSE tolerance is below what this precision can reach ({floor:e})"
            ),
            Self::Length => write!(
                f,
                "PSE: positions, radii, forces and output differ in length"
            ),
            Self::Storage { need, have } => write!(
                f,
                "PSE storage too small: need {need:?} values, have {have:?}"
            ),
        }
    }
}

impl From<PeriodicError> for PseError {
    fn from(e: PeriodicError) -> Self {
        Self::Periodic(e)
    }
}

/// The spheres and the cell list's order of them.
#[derive(Clone, Copy)]
struct Spheres<'a, T: Real> {
    pos: &'a [T::V3],
    radius: &'a [T],
    order: &'a [usize],
}

/// What the wave stage transforms: the spread forces (the product), the spread forces
/// and torques (the grand product, [`Pse::apply_grand`]), or the white noise already
/// drawn on the grid (the Brownian displacement, [`Pse::noise_in`]).
#[derive(Clone, Copy)]
enum Source<'a, T: Real> {
    Force(&'a [T::V3]),
    Grand(&'a [T::V3], &'a [T::V3]),
    Noise,
}

/// Which part of the mobility [`Pse::apply`] applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The whole periodic mobility, `M = M^real + M^wave`.
    Both,
    /// The real-space half `M^real` alone: the near field, with the self blocks' real
    /// parts (the only part that can refuse a configuration: a sphere inside another's
    /// image).
    Near,
    /// The wave-space half `M^wave` alone: spreading, FFT, kernel, inverse FFT,
    /// interpolation.
    Wave,
}

/// Storage sizes of [`Pse::apply`] ([`Pse::storage`]) or [`Pse::apply_grand`]
/// ([`Pse::storage_grand`]) for a given number of spheres.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PseSize {
    /// Complex values: the grid (3 per point, 6 for the grand product), FFT scratch (one per parallel piece),
    /// twiddles and kernel tables.
    pub complex: usize,
    /// Indices: the cell list (one per sphere and one per cell, plus one).
    pub index: usize,
    /// Vectors: one per sphere, two for the grand product (the rows of the near field
    /// and of the interpolation, in the cell list's order).
    pub vectors: usize,
}

/// Caller-owned storage of [`Pse::apply`], at least [`Pse::storage`] (of
/// [`Pse::apply_grand`], at least [`Pse::storage_grand`]), and the
/// [`Parallel`] that runs its pieces ([`Serial`] unless
/// [`PseStorage::with_parallel`]).
pub struct PseStorage<'a, T: Real> {
    complex: &'a mut [Cx<T>],
    index: &'a mut [usize],
    vectors: &'a mut [T::V3],
    parallel: &'a dyn Parallel,
}

impl<'a, T: Real> PseStorage<'a, T> {
    /// Storage over the caller's arrays (sizes checked by [`Pse::apply`]).
    pub fn new(complex: &'a mut [Cx<T>], index: &'a mut [usize], vectors: &'a mut [T::V3]) -> Self {
        Self {
            complex,
            index,
            vectors,
            parallel: &Serial,
        }
    }

    /// Runs the product's pieces through `parallel` (a host's thread pool): the same
    /// bits as [`Serial`], whatever the number of threads.
    pub fn with_parallel(self, parallel: &'a dyn Parallel) -> Self {
        Self { parallel, ..self }
    }
}

/// The PSE parameters of one box, largest radius and tolerance.
#[derive(Clone, Copy, Debug)]
pub struct Pse<T: Real> {
    cell: Periodic<T>,
    a_max: T,
    tol: f64,
    xi: T,
    split: Split<T>,
    grid: fft::Grid3,
    /// Grid spacing per axis.
    h: [T; 3],
    /// The spreading Gaussian's standard deviation and its normalisation.
    sigma: T,
    norm: T,
    /// Gaussian support per axis, in points.
    support: [usize; 3],
    /// `1/(4 xi^2) - sigma^2`: the Gaussian rate left in the wave-space kernel.
    residual: T,
    /// Cell-list cells per axis.
    cells: [usize; 3],
}

impl<T: Real> Pse<T> {
    /// Storage [`Pse::apply`] needs for `n` spheres.
    pub fn storage(&self, n: usize) -> PseSize {
        let [mx, my, mz] = self.grid.m;
        let axes = mx + my + mz;
        PseSize {
            complex: 3 * mx * my * mz + jobs::JOBS * self.grid.scratch_len() + 2 * axes,
            index: n + self.cells[0] * self.cells[1] * self.cells[2] + 1,
            vectors: n,
        }
    }

    /// `out = M F` ([`Part::Both`]): the periodic RPY mobility (viscosity `eta`) of
    /// the spheres at `pos` (any image) with radii `radius` (in `(0, a_max]`) applied
    /// to `force`, to the tolerance; or one half of it ([`Part::Near`], [`Part::Wave`]).
    /// The near field first (row by row), then the wave part added, each in a fixed
    /// order: the same inputs give the same bits. On error `out` is unspecified.
    #[allow(clippy::too_many_arguments)]
    pub fn apply(
        &self,
        part: Part,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        force: &[T::V3],
        out: &mut [T::V3],
        store: &mut PseStorage<'_, T>,
    ) -> Result<(), PseError> {
        self.check(
            eta,
            (pos, radius),
            (force, None),
            out,
            self.storage(pos.len()),
            store,
        )?;
        let n = pos.len();
        let par = store.parallel;
        // The cell list orders the near field's rows and neighbours and the spreading.
        let (order, start) = store.index.split_at_mut(n);
        near::build(self, pos, order, start);
        let (order, start) = (&*order, &*start);
        let rows = &mut store.vectors[..n];
        match part {
            Part::Wave => out.fill(T::V3_ZERO),
            _ => {
                jobs::pieces(par, (&mut *rows, n, 1), jobs::none(), |a, r, _| {
                    near::product(self, eta, (pos, radius), force, (order, start), a, r)
                })?;
                for (&i, &r) in order.iter().zip(rows.iter()) {
                    out[i] = r;
                }
            }
        }
        if part != Part::Near {
            let spheres = Spheres { pos, radius, order };
            let source = Source::Force(force);
            self.wave(
                eta,
                spheres,
                source,
                (store.complex, rows, par),
                (out, None),
            );
        }
        Ok(())
    }

    /// Lengths, storage (at least `size`), viscosity, positions, forces, torques and
    /// radii.
    fn check(
        &self,
        eta: T,
        (pos, radius): (&[T::V3], &[T]),
        (force, torque): (&[T::V3], Option<&[T::V3]>),
        out: &[T::V3],
        size: PseSize,
        store: &PseStorage<'_, T>,
    ) -> Result<(), PseError> {
        let n = pos.len();
        if radius.len() != n || force.len() != n || out.len() != n {
            return Err(PseError::Length);
        }
        if torque.is_some_and(|t| t.len() != n) {
            return Err(PseError::Length);
        }
        let need = [size.complex, size.index, size.vectors];
        let have = [store.complex.len(), store.index.len(), store.vectors.len()];
        if need.iter().zip(&have).any(|(n, h)| h < n) {
            return Err(PseError::Storage { need, have });
        }
        if !(eta > T::ZERO && eta.is_finite()) {
            return Err(PeriodicError::BadParameter("viscosity").into());
        }
        for (i, (&p, &a)) in pos.iter().zip(radius).enumerate() {
            let t = torque.map_or(T::V3_ZERO, |t| t[i]);
            if !T::v3_is_finite(p) || !T::v3_is_finite(force[i]) || !T::v3_is_finite(t) {
                return Err(
                    PeriodicError::Particle(ParticleError::NonFinite { particle: i }).into(),
                );
            }
            if !(a > T::ZERO && a <= self.a_max) {
                return Err(PeriodicError::Radius { particle: i }.into());
            }
        }
        Ok(())
    }
}
