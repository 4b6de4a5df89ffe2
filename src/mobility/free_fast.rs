//! A fast free-space RPY product `u = M F` (translation, [`FreeFast::apply`]) and grand
//! product `(U, W) = M (F, T)` (rotation too, [`FreeFast::apply_grand`]), `O(N log N)`: the
//! positively split product of the periodic box ([`crate::mobility::pse`]) carried to
//! open space.
//!
//! The Stokeslet is split by a Gaussian of variance `s^2 = 4 sigma^2`:
//!
//! * far part: `(1 + a_i^2 lap / 6)(1 + a_j^2 lap / 6)` of the Stokeslet smoothed by the
//!   Gaussian, summed on a grid over the cloud's bounding box: each sphere spread with
//!   the Gaussian of variance `sigma^2` and its sphere factor, the grid convolved
//!   aperiodically (zero-padded to twice its size, the kernel's own FFT) with the
//!   Stokeslet smoothed by the remaining variance `2 sigma^2`, sampled in real space
//!   (smooth, so sampling it is spectrally accurate: no truncated Green's function is
//!   needed), and interpolated back with the same weights;
//! * near part: the exact RPY block (overlapping pairs included) minus the far block,
//!   for the pairs closer than the cutoff (a cell list), and the self blocks; beyond the
//!   cutoff the two agree to the tolerance.
//!
//! One tolerance sets `sigma`'s grid spacing, the window and the cutoff
//! ([`FreeFast::new`], `docs/FREE.md`); [`FreeFast::estimate`] reports the error the
//! chosen parameters give. The caller owns the storage ([`FreeFast::storage`],
//! [`FreeStorage`]); the kernel's transform is computed on the first product and kept
//! in the caller's reals, after a header that records the parameters it is for: a later
//! product, or a later step over the same arrays, whose parameters are bit-identical
//! keeps it (`keep.rs`; [`transform_counts`]). Its work runs in a fixed partition of pieces through the storage's
//! [`Parallel`] ([`FreeStorage::with_parallel`]; `pieces.rs`), each value summed in a
//! fixed order: the same inputs give the same bits on any number of threads.

mod grid;
mod keep;
mod near;
mod pieces;
mod radial;
mod spectral;

use core::fmt;

use crate::cell_list::CellList;
use crate::fault::ParticleError;
use crate::mobility::fft::Cx;
use crate::parallel::{Parallel, Serial};
use crate::real::Real;
use near::{Spheres, partial_len};

pub use keep::{HEADER, TransformCounts};

/// The tolerances [`FreeFast::new`] accepts (from [`min_tolerance`] on in the precision).
pub const MIN_TOLERANCE: f64 = 1e-10;
/// See [`MIN_TOLERANCE`].
pub const MAX_TOLERANCE: f64 = 0.1;
/// Machine epsilons below which no tolerance is accepted (the transforms' rounding, as
/// in PSE): `f32` takes tolerances from about 1.9e-6 on.
pub const EPSILONS: f64 = 16.0;
/// The margin of [`FreeFast::new_grand`]'s rule over [`FreeFast::new`]'s.
pub const GRAND_MARGIN: f64 = 4.0;
/// The largest padded grid edge, in points.
pub const MAX_GRID: usize = 2048;
/// The largest window per axis, in grid points.
pub const MAX_SUPPORT: usize = 40;

/// How often the kernel's transform held in `reals` (a [`FreeStorage`]'s, as the caller
/// passes them) was kept and computed since the arrays were zeroed; `None` where they
/// hold no transform.
pub fn transform_counts<T: Real>(reals: &[T]) -> Option<TransformCounts> {
    keep::counts(reals)
}

/// A cloud's bounding-box edge `edge` (spheres of radius up to `a_max`) rounded up to a
/// coarse step, so that parameters derived from it ([`FreeFast::new`]) stay the same
/// while the edge moves within the step, and the kernel's transform is kept: the step is
/// the smallest `a_max 2^k` above `edge / 32` (at least `a_max`), so the rounding adds
/// under a sixteenth of the edge (or `a_max`). At least `edge`.
pub fn round_extent(edge: f64, a_max: f64) -> f64 {
    if !(edge.is_finite() && a_max > 0.0 && a_max.is_finite()) {
        return edge;
    }
    let mut step = a_max;
    while 32.0 * step <= edge {
        step *= 2.0;
    }
    let up = libm::ceil(edge / step) * step;
    if up < edge { up + step } else { up }
}

/// The smallest tolerance accepted in precision `T`.
pub fn min_tolerance<T: Real>() -> f64 {
    MIN_TOLERANCE.max(EPSILONS * T::EPSILON.to_f64())
}

/// A rejected parameter, configuration or storage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FreeError {
    /// A parameter (named) is not finite, not positive or out of range.
    BadParameter(&'static str),
    /// The tolerance is below what the precision can reach (the floor given).
    Precision {
        /// The smallest tolerance this precision accepts.
        floor: f64,
    },
    /// The cloud needs a grid edge above [`MAX_GRID`] or a window above
    /// [`MAX_SUPPORT`].
    GridTooLarge,
    /// Positions, radii, forces and output differ in length.
    Length,
    /// A sphere the product cannot take: a position or force not finite
    /// ([`ParticleError::NonFinite`]), or one sphere inside another
    /// ([`ParticleError::Nested`]).
    Particle(ParticleError),
    /// A radius outside `(0, a_max]`.
    Radius {
        /// The sphere.
        particle: usize,
    },
    /// The cloud's bounding box exceeds the extent the parameters were sized for.
    Extent,
    /// Caller storage too small: complex values, reals, indices.
    Storage {
        /// Needed.
        need: [usize; 3],
        /// Given.
        have: [usize; 3],
    },
}

impl fmt::Display for FreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadParameter(p) => write!(f, "fast free-space product: bad {p}"),
            Self::Precision { floor } => write!(
                f,
                "the tolerance is below what this precision can reach ({floor:e})"
            ),
            Self::GridTooLarge => write!(f, "the tolerance and cloud need too large a grid"),
            Self::Length => write!(f, "positions, radii, forces and output differ in length"),
            Self::Particle(e) => write!(f, "{e}"),
            Self::Radius { particle } => write!(f, "particle {particle}: radius out of range"),
            Self::Extent => write!(f, "the cloud is larger than the extent it was sized for"),
            Self::Storage { need, have } => {
                write!(f, "storage too small: need {need:?} values, have {have:?}")
            }
        }
    }
}

/// Storage sizes of [`FreeFast::apply`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FreeSize {
    /// Complex values: the padded grid (3 per point), FFT scratch and twiddles.
    pub complex: usize,
    /// Reals: the header of the kept transform ([`HEADER`]), the kernel's transform (one
    /// octant, 6 per point), the cloud's grid (3 per point), and per sphere a row of results and the near part's partial sums.
    pub reals: usize,
    /// Indices: the cell list and each sphere's place in it.
    pub index: usize,
}

/// Caller-owned storage of [`FreeFast::apply`], at least [`FreeFast::storage`], and the
/// [`Parallel`] that runs its pieces ([`Serial`] unless [`FreeStorage::with_parallel`]).
/// It keeps the kernel's transform between products with the same parameters, in
/// `reals` (so between storages over the same arrays: a caller that keeps its arrays
/// between steps keeps the transform; arrays whose first [`HEADER`] reals are zero hold
/// none).
pub struct FreeStorage<'a, T: Real> {
    complex: &'a mut [Cx<T>],
    reals: &'a mut [T],
    index: &'a mut [usize],
    parallel: &'a dyn Parallel,
}

impl<'a, T: Real> FreeStorage<'a, T> {
    /// Storage over the caller's arrays (sizes checked by [`FreeFast::apply`]).
    pub fn new(complex: &'a mut [Cx<T>], reals: &'a mut [T], index: &'a mut [usize]) -> Self {
        Self {
            complex,
            reals,
            index,
            parallel: &Serial,
        }
    }

    /// Runs the product's pieces through `parallel` (a host's thread pool): the same
    /// bits as [`Serial`], whatever the number of threads.
    pub fn with_parallel(self, parallel: &'a dyn Parallel) -> Self {
        Self { parallel, ..self }
    }
}

/// The parameters of the fast free-space product for a largest radius, a tolerance
/// and the largest cloud (bounding box edges and number of spheres).
#[derive(Clone, Copy, Debug)]
pub struct FreeFast<T: Real> {
    a_max: T,
    tol: f64,
    extent: [f64; 3],
    /// The spreading Gaussian's standard deviation; grid spacing; window half-width.
    sigma: f64,
    h: f64,
    reach: f64,
    /// Window points per axis.
    support: usize,
    /// The cloud's grid points per axis and the padded transform's.
    plan: spectral::Plan,
    r_cut: f64,
    estimate: f64,
    /// Made by [`FreeFast::new_grand`].
    grand: bool,
}

impl<T: Real> FreeFast<T> {
    /// Parameters for spheres of radius up to `a_max`, a relative tolerance `tol` in
    /// [`min_tolerance`]`..=`[`MAX_TOLERANCE`], and clouds of `n` spheres whose bounding
    /// box has edges at most `extent`. With `D = ln(12/tol)`:
    ///
    /// * `sigma = max(0.75 a_max, 0.31 (V / n)^{1/3})` (`V` the box's volume): the near
    ///   pairs and the grid points cost alike at `0.31`; the floor keeps the sphere
    ///   factor's growth on the grid (`(a k)^4`) below the tolerance down to 1e-8;
    /// * grid spacing `h = pi sigma sqrt(3 / (2 D))`: the worst aliasing term of the
    ///   double grid sum, `exp(-3 pi^2 sigma^2 / (2 h^2))`, is `exp(-D)`;
    /// * window half-width `sigma sqrt(2 D + 4)`;
    /// * cutoff `r_c = max(2 sigma sqrt(2 (D + 2)), 2 a_max)`: the near part left out,
    ///   `~ erfc(r_c / (2 sqrt(2) sigma))`, below the tolerance, and every overlapping
    ///   pair inside.
    pub fn new(a_max: T, tol: f64, extent: [T; 3], n: usize) -> Result<Self, FreeError> {
        let sigma = Self::rule_sigma(a_max, extent, n);
        Self::with_sigma(a_max, tol, extent, sigma)
    }

    /// [`FreeFast::new`]'s rule with a fourfold margin: parameters for the grand product
    /// ([`FreeFast::apply_grand`]), whose rotations need it (a lone sphere's rotation
    /// reaches twice the tolerance under [`FreeFast::new`]'s parameters). They serve
    /// [`FreeFast::apply`] too, a little more accurately and slowly.
    pub fn new_grand(a_max: T, tol: f64, extent: [T; 3], n: usize) -> Result<Self, FreeError> {
        let sigma = Self::rule_sigma(a_max, extent, n);
        Self::build(a_max, tol, extent, sigma, GRAND_MARGIN)
    }

    /// The spreading width of [`FreeFast::new`]'s rule.
    fn rule_sigma(a_max: T, extent: [T; 3], n: usize) -> T {
        let e = extent.map(|e| e.to_f64());
        let a = a_max.to_f64();
        let vol = e.iter().map(|e| e + 2.0 * a).product::<f64>();
        T::from_f64((0.75 * a).max(0.31 * libm::cbrt(vol / n.max(1) as f64)))
    }

    /// [`FreeFast::new`]'s parameters for a given spreading width `sigma` (at least
    /// `a_max / 2`: narrower, the sphere factors' growth `(a k)^4` spoils the rule).
    pub fn with_sigma(a_max: T, tol: f64, extent: [T; 3], sigma: T) -> Result<Self, FreeError> {
        Self::build(a_max, tol, extent, sigma, 1.0)
    }

    /// [`FreeFast::new_grand`]'s parameters for a given spreading width `sigma` (as
    /// [`FreeFast::with_sigma`]).
    pub fn with_sigma_grand(
        a_max: T,
        tol: f64,
        extent: [T; 3],
        sigma: T,
    ) -> Result<Self, FreeError> {
        Self::build(a_max, tol, extent, sigma, GRAND_MARGIN)
    }

    /// The rule at `tol / margin`.
    fn build(a_max: T, tol: f64, extent: [T; 3], sigma: T, margin: f64) -> Result<Self, FreeError> {
        if !(MIN_TOLERANCE..=MAX_TOLERANCE).contains(&tol) {
            return Err(FreeError::BadParameter("tolerance"));
        }
        let floor = min_tolerance::<T>();
        if tol < floor {
            return Err(FreeError::Precision { floor });
        }
        let a = a_max.to_f64();
        if !(a > 0.0 && a.is_finite()) {
            return Err(FreeError::BadParameter("largest radius"));
        }
        let extent = extent.map(|e| e.to_f64());
        if !extent.iter().all(|e| *e >= 0.0 && e.is_finite()) {
            return Err(FreeError::BadParameter("extent"));
        }
        // The truncations' polynomial prefactors: measured errors reach 6 times
        // `exp(-D)` at 1e-3 (a lone sphere), so the rule runs 12 times below the tolerance.
        let dig = -libm::log(tol) + libm::log(12.0 * margin);
        let sigma = sigma.to_f64();
        if !(sigma >= 0.5 * a && sigma.is_finite()) {
            return Err(FreeError::BadParameter("sigma"));
        }
        let h = PI * sigma * libm::sqrt(1.5 / dig);
        let reach = sigma * libm::sqrt(2.0 * dig + 4.0);
        let support = libm::floor(2.0 * reach / h) as usize + 2;
        if support > MAX_SUPPORT {
            return Err(FreeError::GridTooLarge);
        }
        let mut m = [0; 3];
        for d in 0..3 {
            let need = libm::ceil(extent[d] / h) + support as f64 + 2.0;
            if !(2.0 * need <= MAX_GRID as f64) {
                return Err(FreeError::GridTooLarge);
            }
            m[d] = need as usize;
        }
        let plan = spectral::Plan::new(m).ok_or(FreeError::GridTooLarge)?;
        let r_cut = (2.0 * sigma * libm::sqrt(2.0 * (dig + 2.0))).max(2.0 * a);
        let alias = libm::exp(-1.5 * PI * PI * sigma * sigma / (h * h));
        let window = libm::exp(-0.5 * reach * reach / (sigma * sigma)) * (2.0 * dig + 4.0);
        let near = libm::erfc(r_cut / (2.0 * SQRT_2 * sigma));
        Ok(Self {
            a_max,
            tol,
            extent,
            sigma,
            h,
            reach,
            support,
            plan,
            r_cut,
            estimate: alias + window + near,
            grand: margin >= GRAND_MARGIN,
        })
    }

    /// Storage [`FreeFast::apply`] needs for `n` spheres.
    pub fn storage(&self, n: usize) -> FreeSize {
        FreeSize {
            complex: self.plan.complex_len(),
            reals: HEADER + self.plan.reals_len() + 3 * n + partial_len(n, 3),
            index: 4 * n + 1,
        }
    }

    /// Storage [`FreeFast::apply_grand`] needs for `n` spheres (and [`FreeFast::apply`]).
    pub fn storage_grand(&self, n: usize) -> FreeSize {
        FreeSize {
            reals: HEADER + self.plan.reals_len() + 6 * n + partial_len(n, 6),
            ..self.storage(n)
        }
    }

    /// Whether the parameters serve [`FreeFast::apply_grand`] ([`FreeFast::new_grand`]'s).
    pub fn is_grand(&self) -> bool {
        self.grand
    }
    /// The tolerance the parameters were derived for.
    pub fn tolerance(&self) -> f64 {
        self.tol
    }
    /// The largest bounding-box edges the parameters serve, per axis.
    pub fn extent(&self) -> [f64; 3] {
        self.extent
    }
    /// The relative error the chosen parameters give (the sum of the aliasing, window
    /// and cutoff terms, after rounding): at most about the tolerance.
    pub fn estimate(&self) -> f64 {
        self.estimate
    }
    /// The spreading Gaussian's standard deviation `sigma`.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
    /// The real-space cutoff.
    pub fn r_cut(&self) -> f64 {
        self.r_cut
    }
    /// Padded grid points per axis.
    pub fn grid(&self) -> [usize; 3] {
        self.plan.p
    }
    /// Window points per axis.
    pub fn support(&self) -> usize {
        self.support
    }

    /// `out = M F`: the free-space RPY mobility (viscosity `eta`) of the spheres at
    /// `pos` with radii `radius` in `(0, a_max]` applied to `force`, to the tolerance.
    /// The near part row by row, then the far part added, each in a fixed order. On
    /// error `out` is unspecified and the storage's kernel is kept.
    pub fn apply(
        &self,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        force: &[T::V3],
        out: &mut [T::V3],
        store: &mut FreeStorage<'_, T>,
    ) -> Result<(), FreeError> {
        let s = Spheres {
            pos,
            radius,
            force,
            torque: None,
        };
        self.product(eta, s, (out, None), store)
    }

    /// `(U, W) = M (F, T)`: the free-space RPY grand mobility (viscosity `eta`) of the
    /// spheres at `pos` with radii `radius` in `(0, a_max]` applied to the forces
    /// `force` and torques `torque`: velocities into `vel`, rotations into `spin`, to
    /// the tolerance. The parameters from [`FreeFast::new_grand`] (else
    /// [`FreeError::BadParameter`]), the storage at least [`FreeFast::storage_grand`].
    /// As [`FreeFast::apply`] otherwise.
    #[allow(clippy::too_many_arguments)]
    pub fn apply_grand(
        &self,
        eta: T,
        (pos, radius): (&[T::V3], &[T]),
        force: &[T::V3],
        torque: &[T::V3],
        vel: &mut [T::V3],
        spin: &mut [T::V3],
        store: &mut FreeStorage<'_, T>,
    ) -> Result<(), FreeError> {
        if !self.grand {
            return Err(FreeError::BadParameter(
                "parameters (FreeFast::new_grand's)",
            ));
        }
        if torque.len() != pos.len() || spin.len() != pos.len() {
            return Err(FreeError::Length);
        }
        let s = Spheres {
            pos,
            radius,
            force,
            torque: Some(torque),
        };
        self.product(eta, s, (vel, Some(spin)), store)
    }

    /// The near part into the rows, then the far part added, each in a fixed order.
    fn product(
        &self,
        eta: T,
        s: Spheres<'_, T>,
        (out, mut spin): (&mut [T::V3], Option<&mut [T::V3]>),
        store: &mut FreeStorage<'_, T>,
    ) -> Result<(), FreeError> {
        let lo = self.check(eta, s, out, store)?;
        let (n, w) = (s.pos.len(), s.width());
        let par = store.parallel;
        let cut = T::from_f64(self.r_cut);
        let (cells, rank) = store.index.split_at_mut(3 * n + 1);
        let rank = &mut rank[..n];
        let list = CellList::build::<T>(s.pos, None, cut, cells).map(|(l, _)| l);
        let order = list.as_ref().map(|l| l.order());
        match order {
            Some(o) => o.iter().enumerate().for_each(|(k, &i)| rank[i] = k),
            None => rank.iter_mut().enumerate().for_each(|(i, r)| *r = i),
        }
        let at = |k: usize| order.map_or(k, |o| o[k]);
        let (header, reals) = store.reals.split_at_mut(HEADER);
        let (grid_reals, extra) = reals.split_at_mut(self.plan.reals_len());
        let (rows_buf, partial) = extra.split_at_mut(w * n);
        let ctx = (list.as_ref(), &*rank);
        self.near(eta, s, ctx, (&mut *rows_buf, partial), par)?;
        let v3 = |r: &[T]| T::v3(r[0], r[1], r[2]);
        for (k, r) in rows_buf.chunks_exact(w).enumerate() {
            out[at(k)] = v3(r);
            if let Some(sp) = spin.as_deref_mut() {
                sp[at(k)] = v3(&r[3..]);
            }
        }
        let key = [
            self.plan.p[0] as u64,
            self.plan.p[1] as u64,
            self.plan.p[2] as u64,
            self.plan.m[0] as u64,
            self.plan.m[1] as u64,
            self.plan.m[2] as u64,
            self.h.to_bits(),
            self.sigma.to_bits(),
        ];
        if !keep::keep(header, &key) {
            let before = keep::forget(header);
            grid::kernel(self, store.complex, grid_reals, par);
            keep::done(header, &key, before);
        }
        // Spheres cell by cell: their windows overlap, so the grid stays in cache.
        let storage = (&mut *store.complex, grid_reals, &mut *rows_buf);
        grid::far(self, eta, lo, (s, order), storage, par);
        for (k, r) in rows_buf.chunks_exact(w).enumerate() {
            out[at(k)] += v3(r);
            if let Some(sp) = spin.as_deref_mut() {
                sp[at(k)] += v3(&r[3..]);
            }
        }
        Ok(())
    }

    /// Lengths, storage, viscosity, values, radii and extent; the bounding box's
    /// lower corner.
    fn check(
        &self,
        eta: T,
        s: Spheres<'_, T>,
        out: &[T::V3],
        store: &FreeStorage<'_, T>,
    ) -> Result<[f64; 3], FreeError> {
        let Spheres {
            pos,
            radius,
            force,
            torque,
        } = s;
        let n = pos.len();
        if radius.len() != n || force.len() != n || out.len() != n {
            return Err(FreeError::Length);
        }
        let size = match torque {
            Some(_) => self.storage_grand(n),
            None => self.storage(n),
        };
        let need = [size.complex, size.reals, size.index];
        let have = [store.complex.len(), store.reals.len(), store.index.len()];
        if need.iter().zip(&have).any(|(n, h)| h < n) {
            return Err(FreeError::Storage { need, have });
        }
        if !(eta > T::ZERO && eta.is_finite()) {
            return Err(FreeError::BadParameter("viscosity"));
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (i, (&p, &a)) in pos.iter().zip(radius).enumerate() {
            let t = torque.map_or(T::V3_ZERO, |t| t[i]);
            if !T::v3_is_finite(p) || !T::v3_is_finite(force[i]) || !T::v3_is_finite(t) {
                return Err(FreeError::Particle(ParticleError::NonFinite {
                    particle: i,
                }));
            }
            if !(a > T::ZERO && a <= self.a_max) {
                return Err(FreeError::Radius { particle: i });
            }
            let p = T::v3_to_f64(p);
            for d in 0..3 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        if (0..3).any(|d| hi[d] - lo[d] > self.extent[d]) {
            return Err(FreeError::Extent);
        }
        Ok(lo)
    }
}

const PI: f64 = core::f64::consts::PI;
const SQRT_2: f64 = core::f64::consts::SQRT_2;
