//! The PSE parameters from one tolerance (`docs/PERIODIC.md`, section PSE), and their
//! accessors.

use super::{MAX_GRID, MAX_SUPPORT, Pse, PseError, XI_PSE, fft, good_size};

/// Cell-list cells per axis at most (a bound on the index storage of a large, dilute
/// box: 128^3 cells).
const MAX_CELLS: usize = 128;
use crate::mobility::periodic::real::Split;
use crate::mobility::periodic::{Periodic, PeriodicError};
use crate::real::Real;

impl<T: Real> Pse<T> {
    /// Parameters by the documented rule with `xi = XI_PSE / a_max`.
    pub fn new(cell: Periodic<T>, a_max: T, tol: f64) -> Result<Self, PseError> {
        Self::with_xi(cell, a_max, tol, T::from_f64(XI_PSE) / a_max)
    }

    /// Parameters for a splitting parameter `xi` and a relative tolerance
    /// `tol` in `[1e-12, 0.1]` (from [`min_tolerance`](super::min_tolerance) on in the
    /// precision `T`), spheres of radius below
    /// [`MAX_RADIUS_FRACTION`](super::MAX_RADIUS_FRACTION) of the smallest edge. With
    /// `D = ln(1/tol)`:
    ///
    /// * `p^2 = D + 3/2 ln(p^2) + 2 ln(1 + (a_max xi p)^2 / 2)` (a fixed point): the
    ///   Ewald path's rule (the last term, the sphere factors' growth) plus the growth
    ///   of the number of wave vectors in a shell, `~ p^3`, which dominates the
    ///   wave-space tail;
    /// * real-space cutoff `r_c = max(p / xi, 2 a_max)`, wave-space cutoff
    ///   `k_max = 2 p xi`: both truncations `~ exp(-p^2)`;
    /// * grid spacing `h_d <= pi / k_max` (the Nyquist wave number at `k_max`; each
    ///   edge rounded up to an even `2^a 3^b 5^c` number of points);
    /// * Gaussian `sigma = p / (sqrt(2) k_max)`: its aliasing error
    ///   `exp(-2 pi^2 sigma^2 / h^2)` is at most `exp(-p^2)`; the kernel keeps
    ///   `exp(-k^2 / (8 xi^2))` (half of Hasimoto's Gaussian) between the two spreads;
    /// * support `P_d = ceil(2 sqrt(2 D) sigma / h_d)` points (about `2 p sqrt(D) / pi`):
    ///   the Gaussian left out is below `exp(-D)` of its peak.
    ///
    /// Measured against the Ewald path the error is 5 to 50 times below `tol`
    /// (`docs/PERIODIC.md`).
    pub fn with_xi(cell: Periodic<T>, a_max: T, tol: f64, xi: T) -> Result<Self, PseError> {
        if !(xi > T::ZERO && xi.is_finite()) {
            return Err(PeriodicError::BadParameter("xi").into());
        }
        if !(super::MIN_TOLERANCE..=super::MAX_TOLERANCE).contains(&tol) {
            return Err(PeriodicError::BadParameter("tolerance").into());
        }
        if !(a_max > T::ZERO && a_max.is_finite()) {
            return Err(PeriodicError::BadParameter("largest radius").into());
        }
        let size = cell.size();
        let smallest = size[0].min(size[1]).min(size[2]);
        if !(a_max + a_max < smallest) {
            return Err(PeriodicError::SphereTooLarge.into());
        }
        if !(a_max.to_f64() < super::MAX_RADIUS_FRACTION * smallest.to_f64()) {
            return Err(PseError::LargeSphere);
        }
        let floor = super::min_tolerance::<T>();
        if tol < floor {
            return Err(PseError::Precision { floor });
        }
        // The rule in f64 whatever T.
        let (x, a, dig) = (xi.to_f64(), a_max.to_f64(), -libm::log(tol));
        let mut p2 = dig;
        for _ in 0..6 {
            let t = a * x * libm::sqrt(p2);
            p2 = dig + 1.5 * libm::log(p2) + 2.0 * libm::log(1.0 + 0.5 * t * t);
        }
        let p = libm::sqrt(p2);
        let r_cut = (p / x).max(2.0 * a);
        let k_max = 2.0 * p * x;
        let sigma = libm::sqrt(0.5 * p2) / k_max;
        let width = 2.0 * libm::sqrt(2.0 * dig) * sigma;
        let (mut m, mut h, mut support, mut cells) = ([0; 3], [T::ZERO; 3], [0; 3], [1; 3]);
        let mut factors = [fft::Factors::new(1).ok_or(PseError::GridTooLarge)?; 3];
        for d in 0..3 {
            let l = size[d].to_f64();
            let need = libm::ceil(l * k_max / core::f64::consts::PI);
            if !(need <= MAX_GRID as f64) {
                return Err(PseError::GridTooLarge);
            }
            m[d] = good_size(need as usize);
            factors[d] = fft::Factors::new(m[d]).ok_or(PseError::GridTooLarge)?;
            let hd = l / m[d] as f64;
            h[d] = T::from_f64(hd);
            let s = libm::ceil(width / hd);
            // A support wider than the box is fine: the window then visits a point once
            // per image of the sphere, each with that image's weight (the periodic sum).
            if !(s <= MAX_SUPPORT as f64) {
                return Err(PseError::GridTooLarge);
            }
            support[d] = s as usize;
            // At most MAX_CELLS per axis: wider cells are still at least r_c wide.
            cells[d] = (libm::floor(l / r_cut) as usize).clamp(1, MAX_CELLS);
        }
        let norm = libm::pow(2.0 * core::f64::consts::PI * sigma * sigma, -1.5);
        Ok(Self {
            cell,
            a_max,
            tol,
            xi,
            split: Split::new(cell, xi, r_cut)?,
            grid: fft::Grid3 {
                m,
                factors,
                comps: 3,
            },
            h,
            sigma: T::from_f64(sigma),
            norm: T::from_f64(norm),
            support,
            residual: T::from_f64(0.25 / (x * x) - sigma * sigma),
            cells,
        })
    }

    /// The box.
    pub fn cell(&self) -> Periodic<T> {
        self.cell
    }
    /// The splitting parameter.
    pub fn xi(&self) -> T {
        self.xi
    }
    /// The tolerance the parameters were derived for.
    pub fn tolerance(&self) -> f64 {
        self.tol
    }
    /// The real-space cutoff.
    pub fn r_cut(&self) -> T {
        self.split.r_cut
    }
    /// Grid points per axis.
    pub fn grid(&self) -> [usize; 3] {
        self.grid.m
    }
    /// Gaussian support per axis, in grid points.
    pub fn support(&self) -> [usize; 3] {
        self.support
    }
    /// Cell-list cells per axis.
    pub fn cells(&self) -> [usize; 3] {
        self.cells
    }
    /// The largest radius the parameters were chosen for.
    pub fn a_max(&self) -> T {
        self.a_max
    }
}
