//! The mobility above a no-slip plane wall: the polydisperse RPY tensor plus the image
//! system of Blake's solution with Faxén corrections (Swan & Brady, Phys. Fluids 19,
//! 113306, 2007), derived for unequal radii in `docs/WALL.md` (the formulas here are
//! that document's, term for term). Translation here; the rotation blocks (the grand
//! mobility, spins) in [`assemble_grand`] and [`add_spin`].
//!
//! The wall is the plane `z = height`, the spheres above it. With `h_i = z_i - height`,
//! the block `(i, j)` is the free-space block plus the image block
//! `(1 + a_i^2/6 lap_i)(1 + a_j^2/6 lap_j)` of Blake's image system, a function of
//! `R = (x_i - x_j, y_i - y_j, h_i + h_j)` (from the mirror image of `j` to `i`) and
//! `h_j`:
//!
//! `8 pi eta W_ij = f1 I + f2 e e^T + f3 e z^T + f4 z e^T + f5 z z^T`, `e = R/|R|`,
//! `z` the wall's normal ([`image_tt`]). The self block of a lone sphere is diagonal,
//! `mu_par` along the wall and `mu_perp` across it ([`self_wall`]).
//!
//! **Positive definiteness.** For spheres wholly above the wall (`h_i >= a_i`) the
//! mobility is the average of Blake's Green's function over the two spheres' surfaces,
//! so it is positive definite (`docs/WALL.md`). A sphere whose centre comes closer,
//! `0 < h_i < a_i` (the wall's contacts allow it within their tolerance; without
//! contacts nothing prevents it), is treated as RigidMultiblobsWall does: its centre is
//! lifted to `h_i = a_i` for the evaluation and its rows and columns are damped by
//! `h_i / a_i` (`B M B` with `B` diagonal and positive: still positive definite). A
//! centre at or below the plane is refused ([`ParticleError::BelowWall`]).
//!
//! **Levels.** [`Hydro::Rpy`]: the above. [`Hydro::FreeDraining`]: the self blocks
//! only (the single-sphere wall mobility), no pair terms. [`Hydro::Oseen`]: the free
//! Oseen tensor plus Blake's point-force image (the image block with zero radii), and
//! the RPY self blocks; like Oseen in free space, not positive definite at short range.
//!
//! Blocks `(i, j)` and `(j, i)` are transposes of each other, not symmetric 3x3 blocks:
//! the packed storage keeps `(i, j)` for `i > j` and every reader of the other triangle
//! transposes ([`tt_block_at`] returns the block in the orientation asked for).

mod rotation;
pub use rotation::{add_spin, assemble_grand, image_rot, self_wall_rot};

use crate::fault::ParticleError;
use crate::linalg::tri;
use crate::mobility::{Hydro, pair_tt, self_tt};
use crate::parallel::{
    Blocks, Parallel, assemble_blocks, block_at, product_blocks, serial_product,
};
use crate::real::Real;

/// `(mu_par, mu_perp)`: Swan & Brady's self mobility of a sphere of radius `a` whose
/// centre is at height `h` (`>= a`) above the wall, along and across it:
/// `mu_par = (1 - 9/16 x + 1/8 x^3 - 1/16 x^5) / (6 pi eta a)`,
/// `mu_perp = (1 - 9/8 x + 1/2 x^3 - 1/8 x^5) / (6 pi eta a)`, `x = a / h`.
pub fn self_wall<T: Real>(eta: T, a: T, h: T) -> (T, T) {
    let c = |v: f64| T::from_f64(v);
    let x = a / h;
    let x3 = x * x * x;
    let x5 = x3 * x * x;
    let s = self_tt(eta, a);
    let par = s * (T::ONE - c(9.0 / 16.0) * x + c(0.125) * x3 - c(0.0625) * x5);
    let perp = s * (T::ONE - c(1.125) * x + c(0.5) * x3 - c(0.125) * x5);
    (par, perp)
}

/// The image block `W_ij` (velocity of `i` per unit force on `j`) for radii `a_i`,
/// `a_j`, `r = r_i - r_j` (only its wall-parallel part is read), `rz = h_i + h_j` and
/// the source's height `hj` (`docs/WALL.md`, eq. W). Zero radii give Blake's point-force
/// image. Not symmetric; `W_ji = W_ij^T`.
#[inline(always)]
pub fn image_tt<T: Real>(eta: T, ai: T, aj: T, r: T::V3, rz: T, hj: T) -> T::M3 {
    let c = |v: f64| T::from_f64(v);
    let [rx, ry, _] = T::xyz(r);
    let big = T::v3(rx, ry, rz);
    let (_, u) = T::norm2(big).root_and_inverse();
    let e = big * u;
    let ez = rz * u;
    let ez2 = ez * ez;
    // Dimensionless: t = h_j / R, alpha = a_i^2 / R^2, beta = a_j^2 / R^2.
    let t = hj * u;
    let alpha = ai * ai * u * u;
    let beta = aj * aj * u * u;
    let delta = alpha - beta;
    let ab = alpha * beta;
    let two = T::TWO;
    let f1 = -T::ONE - two * ez * t + two * t * t - (alpha + beta) * c(1.0 / 3.0)
        + two * beta * ez2
        + two * delta * ez * t
        + ab * (c(2.0 / 3.0) - c(10.0 / 3.0) * ez2);
    let f2 = -T::ONE + c(6.0) * ez * t - c(6.0) * t * t + (alpha + beta)
        - c(10.0) * beta * ez2
        - c(10.0) * delta * ez * t
        + ab * (c(70.0 / 3.0) * ez2 - c(10.0 / 3.0));
    let f3 = two * t - c(12.0) * ez2 * t
        + c(12.0) * ez * t * t
        + beta * ez * (c(20.0) * ez2 - c(4.0))
        + delta * t * (c(20.0) * ez2 - two)
        + ab * ez * (c(40.0 / 3.0) - c(140.0 / 3.0) * ez2);
    let f4 = two * t + two * delta * t - c(20.0 / 3.0) * ab * ez;
    let f5 = c(-4.0) * t * t - c(4.0) * beta * ez2 - c(8.0) * delta * ez * t
        + ab * (c(20.0) * ez2 - c(8.0 / 3.0));
    // Columns of f1 I + f2 e e^T + f3 e z^T + f4 z e^T + f5 z z^T, times 1/(8 pi eta R).
    let k = u * (T::ONE / (c(8.0) * T::PI * eta));
    let [ex, ey, _] = T::xyz(e);
    let zhat = T::v3(T::ZERO, T::ZERO, T::ONE);
    let col = |unit: T::V3, ek: T| unit * f1 + e * (f2 * ek) + zhat * (f4 * ek);
    let c0 = col(T::v3(T::ONE, T::ZERO, T::ZERO), ex);
    let c1 = col(T::v3(T::ZERO, T::ONE, T::ZERO), ey);
    let c2 = zhat * (f1 + f4 * ez + f5) + e * (f2 * ez + f3);
    T::m3_cols(c0 * k, c1 * k, c2 * k)
}

/// A sphere as the wall's mobility sees it: its centre (lifted to `h = a` when closer),
/// that height, and the damping factor `min(1, h / a)`.
#[derive(Clone, Copy)]
struct Lifted<T: Real> {
    p: T::V3,
    h: T,
    b: T,
}

/// Sphere `i` at `p` of radius `a` above the wall at `height`; an error when its centre
/// is not above the plane.
#[inline(always)]
fn lift<T: Real>(height: T, a: T, p: T::V3, i: usize) -> Result<Lifted<T>, ParticleError> {
    let [x, y, z] = T::xyz(p);
    let h = z - height;
    if !(h > T::ZERO) {
        return Err(ParticleError::BelowWall { particle: i });
    }
    if h >= a {
        return Ok(Lifted { p, h, b: T::ONE });
    }
    Ok(Lifted {
        p: T::v3(x, y, height + a),
        h: a,
        b: h / a,
    })
}

/// The self block: `diag(mu_par, mu_par, mu_perp)` (damped by `b^2`).
#[inline(always)]
fn self_block<T: Real>(eta: T, a: T, s: Lifted<T>) -> T::M3 {
    let (par, perp) = self_wall(eta, a, s.h);
    let b2 = s.b * s.b;
    let (par, perp) = (par * b2, perp * b2);
    T::m3_cols(
        T::v3(par, T::ZERO, T::ZERO),
        T::v3(T::ZERO, par, T::ZERO),
        T::v3(T::ZERO, T::ZERO, perp),
    )
}

/// The block `(i, j)`, `i != j`: free space plus image, damped; `None` for nested
/// spheres.
#[inline(always)]
fn pair<T: Real>(
    level: Hydro,
    eta: T,
    ai: T,
    aj: T,
    si: Lifted<T>,
    sj: Lifted<T>,
) -> Option<T::M3> {
    let r = si.p - sj.p;
    let free = pair_tt(level, eta, ai, aj, r)?;
    let (ri, rj) = match level {
        Hydro::FreeDraining => return Some(free),
        Hydro::Oseen => (T::ZERO, T::ZERO),
        Hydro::Rpy => (ai, aj),
    };
    let image = image_tt(eta, ri, rj, r, si.h + sj.h, sj.h);
    Some((free + image) * (si.b * sj.b))
}

/// `mu_tt` above the wall at `height`, block by block, as the band loops of
/// [`crate::parallel`] read it: a sphere's site is its lift (an error below the wall).
#[derive(Clone, Copy)]
struct Wall<'a, T: Real> {
    level: Hydro,
    eta: T,
    height: T,
    pos: &'a [T::V3],
    radius: &'a [T],
}

impl<'a, T: Real> Wall<'a, T> {
    #[inline(always)]
    fn new(level: Hydro, eta: T, height: T, pos: &'a [T::V3], radius: &'a [T]) -> Self {
        Self {
            level,
            eta,
            height,
            pos,
            radius,
        }
    }
}

impl<T: Real> Blocks<T> for Wall<'_, T> {
    type Site = Lifted<T>;
    type Error = ParticleError;
    #[inline(always)]
    fn site(&self, i: usize) -> Result<Lifted<T>, ParticleError> {
        lift(self.height, self.radius[i], self.pos[i], i)
    }
    #[inline(always)]
    fn diag(&self, i: usize, si: Lifted<T>) -> T::M3 {
        self_block(self.eta, self.radius[i], si)
    }
    #[inline(always)]
    fn pair(
        &self,
        i: usize,
        si: Lifted<T>,
        j: usize,
        sj: Lifted<T>,
    ) -> Result<T::M3, ParticleError> {
        let (ai, aj) = (self.radius[i], self.radius[j]);
        pair(self.level, self.eta, ai, aj, si, sj).ok_or(ParticleError::Nested { i: j, j: i })
    }
}

/// Block `(p, q)` of `mu_tt` above the wall at `height`, in that orientation (the
/// stored block `(max, min)`, transposed when `p < q`).
pub fn tt_block_at<T: Real>(
    level: Hydro,
    eta: T,
    height: T,
    pos: &[T::V3],
    radius: &[T],
    p: usize,
    q: usize,
) -> Result<T::M3, ParticleError> {
    let src = Wall::new(level, eta, height, pos, radius);
    block_at(&src, true, p, q)
}

/// Assembles `mu_tt` above the wall at `height` (packed lower triangle, [`tri`]`(n)`
/// blocks), in bands through `par` (the bands of [`crate::parallel`]: the same blocks on
/// any number of threads, the first error in row order).
pub fn assemble<T: Real>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    height: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), ParticleError> {
    let src = Wall::new(level, eta, height, pos, radius);
    let none = (&mut [][..], tri as fn(usize) -> usize);
    assemble_blocks(par, pos.len(), &src, out, none, |_, _, _, _| {})
}

/// `y = mu_tt x` above the wall without storing `mu_tt`, in the bands of
/// [`crate::parallel::product`] through `par` (`z`: at least
/// [`band_scratch`](crate::parallel::band_scratch)`(n)` vectors): the bits of
/// [`assemble`] then [`crate::parallel::product`] at every `n` and on any number of
/// threads (below [`BANDED_MIN`](crate::parallel::BANDED_MIN) rows those of
/// [`tt_product`]). The first error of [`tt_product`]: a sphere below the wall (in
/// particle order), then nested spheres in row order.
#[allow(clippy::too_many_arguments)]
pub fn free_product<T: Real>(
    par: &dyn Parallel,
    level: Hydro,
    eta: T,
    height: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), ParticleError> {
    let src = Wall::new(level, eta, height, pos, radius);
    product_blocks(par, &src, &x[..pos.len()], y, z)
}

/// `y = mu_tt x` above the wall without storing `mu_tt`, in the order of [`assemble`]
/// followed by [`sym_matvec`](crate::linalg::sym_matvec) (the same bits below
/// [`BANDED_MIN`](crate::parallel::BANDED_MIN) rows, as in free space); one thread
/// ([`free_product`] runs in bands). A sphere below the wall (in particle order), then
/// nested spheres in row order.
pub fn tt_product<T: Real>(
    level: Hydro,
    eta: T,
    height: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
) -> Result<(), ParticleError> {
    let src = Wall::new(level, eta, height, pos, radius);
    serial_product(&src, &x[..pos.len()], y)
}
