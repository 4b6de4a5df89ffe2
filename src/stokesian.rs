//! The dense Stokesian dynamics mobility of `N` spheres in free space, above the wall or
//! in a periodic box ([`Far`]): `M_SD = R^-1`, `R = M_far^-1 + sum R_near`, translation
//! and rotation (`6N x 6N`). The iterative product for large `N` is [`iterative`].
//!
//! * `M_far`: the geometry's RPY grand mobility, through the kernel's geometry
//!   interface ([`Far::assemble_grand`]: [`crate::mobility::assemble_grand`] in free
//!   space, [`crate::mobility::wall::assemble_grand`] above the wall, the Ewald sums'
//!   `crate::mobility::periodic::assemble_grand` in the box). A geometry's own part
//!   lives in its file here: the box's far field (`periodic.rs`), the wall's sphere
//!   corrections (`wall.rs`).
//! * Pairs whose surface gap is below [`NearField::cutoff`] mean radii (in the box, at
//!   their minimum image, and only while it is shorter than half the smallest edge, so
//!   that a pair has one image at most): the pair's
//!   [`crate::near::near_correction`], `R_2B,exact - (pair RPY 12x12 mobility in free
//!   space)^-1` (above the wall too: the wall enters the pair only through `M_far`).
//! * Spheres whose gap to the wall is below [`NearField::wall_cutoff`] radii: the exact
//!   sphere-wall resistance ([`crate::near::wall::wall_scalars`]) minus the inverse of the
//!   sphere's own 6x6 wall mobility block (RPY self term with its wall reflections,
//!   [`crate::mobility::wall::self_wall`] and [`crate::mobility::wall::self_wall_rot`]):
//!   [`wall_correction`], the iterative product's too.
//! * A pair or a sphere closer than [`NearField::min_gap`] (overlaps included, which RPY
//!   allows) gets the correction of the minimum gap, along the same line of centres
//!   (clamped): a surface roughness. Its far part is evaluated at the clamped gap too, so
//!   the correction is still a two-body `R_exact - R_far`.
//!
//! Positive definite: `M_far` is, and each pair's correction is semi-definite (checked in
//! `docs/NEAR.md`), so `R` is; its Cholesky factor failing is reported, not hidden.
//! With no pair or sphere inside its cutoff the result is `M_far` itself, bit for bit.
//!
//! Storage is the caller's ([`storage`]); the output is row-major `6N x 6N`, rows and
//! columns `(U_0 .. U_{N-1}, W_0 .. W_{N-1})`, three each, as the grand mobility is laid
//! out. Cost: two dense Cholesky inversions, about `(6N)^3 4/3` flops, and `O(N^2)`
//! distance tests.

mod far;
pub mod iterative;
#[cfg(feature = "periodic")]
mod periodic;
mod wall;

pub use far::Far;
pub use wall::{SphereBlocks, wall_correction};

use crate::error::{LinalgError, ParticleError, StepError};
use crate::linalg::{spd_inverse, tri};
use crate::mobility::{Hydro, pair_blocks, self_rr, self_tt};
use crate::near::{NearError, near_correction};
use crate::real::Real;

/// The near field's parameters, in units of the spheres' radii.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearField<T> {
    /// Pairs whose surface gap is below `cutoff` mean radii (`xi = s - 2 < cutoff`,
    /// `s = 2 r / (a1 + a2)`) are corrected. Default 4 (`s < 6`, where RPY is within
    /// 0.2 % of the exact pair: the correction's jump there).
    pub cutoff: T,
    /// Spheres whose surface is nearer the wall than `wall_cutoff` radii (`h / a - 1`)
    /// are corrected. Default 4 (`h < 5 a`, where the far field's perpendicular
    /// mobility is within 0.2 % of the exact).
    pub wall_cutoff: T,
    /// The smallest gap the near field sees (surface roughness), for pairs in mean radii,
    /// for the wall in radii; closer pairs and spheres, overlaps included, get the
    /// correction of this gap. Default `1e-3`.
    pub min_gap: T,
}

impl<T: Real> Default for NearField<T> {
    fn default() -> Self {
        Self {
            cutoff: T::from_f64(4.0),
            wall_cutoff: T::from_f64(4.0),
            min_gap: T::from_f64(1e-3),
        }
    }
}

/// Why the Stokesian dynamics mobility was not formed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SdError {
    /// The far field refused the spheres (nested spheres, a centre below the wall, a
    /// radius above the box sums' largest, a sphere inside another's image).
    Particle(ParticleError),
    /// The far field's geometry refused its grand mobility otherwise: its step's error
    /// ([`Far::assemble_grand`]).
    Far(StepError),
    /// A pair's near field has no value (a size ratio outside `0.1..=10`, a radius that
    /// is not positive), or a sphere's wall functions.
    Near {
        /// First sphere.
        i: usize,
        /// Second sphere (`i` for the wall).
        j: usize,
        /// The near-field module's reason.
        why: NearError,
    },
    /// `M_far` or `R` is not positive definite in this precision.
    NotPositiveDefinite(LinalgError),
    /// A parameter is not finite, a cutoff is negative or `min_gap` is not positive (or,
    /// for [`iterative`], a tolerance that is not positive), or the far field names a
    /// geometry the kernel was built without.
    Params,
    /// The storage is shorter than [`storage`] asks.
    Storage,
    /// The iterative product did not reach its tolerance within its iterations
    /// ([`iterative`]): the relative residual it stopped at.
    NotConverged {
        /// Iterations done.
        iterations: u32,
        /// The relative residual reached (`f64` whatever the precision).
        residual: f64,
    },
}

/// The storage [`mobility`] needs for `n` spheres: `(packed blocks, dense scalars)`,
/// `tri(2n)` 3x3 blocks and `(6n)^2` entries of `T` (the output).
pub fn storage(n: usize) -> (usize, usize) {
    (tri(2 * n), 36usize.saturating_mul(n).saturating_mul(n))
}

/// The Stokesian dynamics grand mobility of the spheres at `pos` with radii `radius`, in
/// a fluid of viscosity `eta`, above the wall at height `wall` if given; into `out`
/// (`(6n)^2`, row-major), with `packed` as scratch ([`storage`]). On an error `out` and
/// `packed` hold no meaningful values (they are the caller's buffers, not state).
/// [`mobility_in`] with [`Far::above`] or [`Far::FREE`].
pub fn mobility<T: Real>(
    eta: T,
    wall: Option<T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    packed: &mut [T::M3],
    out: &mut [T],
) -> Result<(), SdError> {
    let far = wall.map_or(Far::FREE, Far::above);
    mobility_in(eta, far, pos, radius, near, packed, out)
}

/// The Stokesian dynamics grand mobility in the geometry `far` (as [`mobility`]).
pub fn mobility_in<T: Real>(
    eta: T,
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    packed: &mut [T::M3],
    out: &mut [T],
) -> Result<(), SdError> {
    let n = pos.len().min(radius.len());
    let (nb, nd) = storage(n);
    let (Some(packed), Some(out)) = (packed.get_mut(..nb), out.get_mut(..nd)) else {
        return Err(SdError::Storage);
    };
    near.check()?;
    let (pos, radius) = (&pos[..n], &radius[..n]);
    let wall = far.wall();
    far.assemble_grand(eta, pos, radius, packed)?;
    let m = 6 * n;
    for bi in 0..2 * n {
        for bj in 0..=bi {
            let b = packed[tri(bi) + bj];
            for r in 0..3 {
                for c in 0..3 {
                    let v = T::m3_get(b, r, c);
                    out[(3 * bi + r) * m + 3 * bj + c] = v;
                    out[(3 * bj + c) * m + 3 * bi + r] = v;
                }
            }
        }
    }
    let pairs = close_pairs(far, pos, radius, near.cutoff);
    let walls = wall.map_or(0, |h| close_walls(h, pos, radius, near.wall_cutoff));
    if pairs == 0 && walls == 0 {
        return Ok(());
    }
    spd_inverse(out, m).map_err(SdError::NotPositiveDefinite)?;
    add_pairs(eta, far, pos, radius, near, out)?;
    if let Some(h) = wall {
        wall::add_walls(eta, h, pos, radius, near, out)?;
    }
    spd_inverse(out, m).map_err(SdError::NotPositiveDefinite)
}

impl<T: Real> NearField<T> {
    /// `Err(SdError::Params)` unless the cutoffs are finite and not negative and
    /// `min_gap` finite and positive.
    pub fn check(&self) -> Result<(), SdError> {
        let ok = |v: T| v.is_finite() && v >= T::ZERO;
        match ok(self.cutoff) && ok(self.wall_cutoff) && ok(self.min_gap) && self.min_gap > T::ZERO
        {
            true => Ok(()),
            false => Err(SdError::Params),
        }
    }
}

/// The scaled surface gap `xi = 2 r / (a1 + a2) - 2` of spheres `i` and `j`, and `r`
/// (from `i` to `j`, the minimum image in the box).
fn gap<T: Real>(far: Far<'_, T>, pos: &[T::V3], radius: &[T], i: usize, j: usize) -> (T, T::V3) {
    let r = far.separation(pos[i], pos[j]);
    let s = T::norm2(r).sqrt() * T::TWO / (radius[i] + radius[j]);
    match far.unique(r) {
        true => (s - T::TWO, r),
        // Beyond every (finite) cutoff.
        false => (T::ONE / T::MIN_POSITIVE, r),
    }
}

/// How many pairs are inside the cutoff.
fn close_pairs<T: Real>(far: Far<'_, T>, pos: &[T::V3], radius: &[T], cutoff: T) -> usize {
    let n = pos.len();
    (0..n)
        .map(|i| {
            (i + 1..n)
                .filter(|&j| gap(far, pos, radius, i, j).0 < cutoff)
                .count()
        })
        .sum()
}

/// How many spheres are inside the wall's cutoff.
fn close_walls<T: Real>(height: T, pos: &[T::V3], radius: &[T], cutoff: T) -> usize {
    (0..pos.len())
        .filter(|&i| wall::gap(height, pos[i], radius[i]) < cutoff)
        .count()
}

/// Adds `m` (rows `rows`, columns `cols`, 3 each) into the dense `out`.
fn add_block<T: Real>(out: &mut [T], m: usize, (bi, bj): (usize, usize), b: T::M3) {
    for r in 0..3 {
        for c in 0..3 {
            out[(3 * bi + r) * m + 3 * bj + c] += T::m3_get(b, r, c);
        }
    }
}

/// Adds every close pair's `R_near` to the resistance in `out`.
fn add_pairs<T: Real>(
    eta: T,
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    out: &mut [T],
) -> Result<(), SdError> {
    let n = pos.len();
    let m = 6 * n;
    for i in 0..n {
        for j in i + 1..n {
            let Some(c) = pair_correction(eta, far, pos, radius, near, (i, j))? else {
                continue;
            };
            let idx = [i, j, n + i, n + j];
            for (bi, row) in c.iter().enumerate() {
                for (bj, &b) in row.iter().enumerate() {
                    add_block::<T>(out, m, (idx[bi], idx[bj]), b);
                }
            }
        }
    }
    Ok(())
}

/// The near-field correction `R_near` of the pair `(i, j)` (rows and columns
/// `(1, 2, rotation 1, rotation 2)`), `None` beyond the cutoff or at coincident centres.
#[allow(clippy::type_complexity)]
pub fn pair_correction<T: Real>(
    eta: T,
    far: Far<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    near: NearField<T>,
    (i, j): (usize, usize),
) -> Result<Option<[[T::M3; 4]; 4]>, SdError> {
    let (xi, r) = gap(far, pos, radius, i, j);
    if !(xi < near.cutoff) {
        return Ok(None);
    }
    let (a1, a2) = (radius[i], radius[j]);
    let len = T::norm2(r).sqrt();
    if !(len > T::ZERO) {
        // Coincident centres: no line of centres; RPY alone (positive definite).
        return Ok(None);
    }
    let d = r * (T::ONE / len);
    let xi = if xi < near.min_gap { near.min_gap } else { xi };
    let dist = (a1 + a2) * T::HALF * (T::TWO + xi);
    let pf = pair_far(eta, a1, a2, d * dist);
    let why = |why| SdError::Near { i, j, why };
    near_correction(eta, a1, a2, d * dist, &pf)
        .map(Some)
        .map_err(why)
}

/// The free-space RPY 12x12 mobility of a pair, sphere 2 at `r` from sphere 1, as
/// [`near_correction`] takes it (rows `(U1, U2, W1, W2)`, columns `(F1, F2, T1, T2)`).
pub fn pair_far<T: Real>(eta: T, a1: T, a2: T, r: T::V3) -> [[T::M3; 4]; 4] {
    let z = T::M3_ZERO;
    let mut f = [[z; 4]; 4];
    f[0][0] = T::m3_diag(self_tt(eta, a1));
    f[1][1] = T::m3_diag(self_tt(eta, a2));
    f[2][2] = T::m3_diag(self_rr(eta, a1));
    f[3][3] = T::m3_diag(self_rr(eta, a2));
    // Apart (s > 2 after clamping), so the blocks exist; zero coupling otherwise.
    if let Some(p) = pair_blocks(Hydro::Rpy, eta, a1, a2, -r) {
        f[0][1] = p.tt;
        f[1][0] = T::transpose(p.tt);
        f[2][1] = p.rt_ij;
        f[1][2] = T::transpose(p.rt_ij);
        f[3][0] = p.rt_ji;
        f[0][3] = T::transpose(p.rt_ji);
        f[2][3] = p.rr;
        f[3][2] = T::transpose(p.rr);
    }
    f
}
