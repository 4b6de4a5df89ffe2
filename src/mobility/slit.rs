//! The mobility between two parallel no-slip walls, a floor `z = floor` and a ceiling
//! `z = ceiling > floor`, by the linear superposition approximation (Swan & Brady,
//! "Particle motion between parallel walls", J. Fluid Mech. 662, 2010): the free-space
//! RPY blocks plus each wall's correction, the floor's image system of `mobility::wall`
//! and the ceiling's, which is the floor's seen in the mirror `z -> 2 ceiling - z`.
//!
//! **The mirror.** Under `P = diag(1, 1, -1)` forces and velocities are vectors and
//! angular velocities and torques pseudovectors (`w -> -P w`), so a ceiling's block is
//! the floor's block of the mirrored spheres conjugated: `P W P` for translation-
//! translation and rotation-rotation, `-P W P` for the couplings. The wall's image
//! blocks read the wall-parallel separation and the heights above the plane only, so
//! the mirrored spheres' blocks are the wall's functions at the heights below the
//! ceiling: no block is written twice.
//!
//! **Where superposition fails.** It is not Blake's solution for two walls: each
//! wall's image ignores the other's, so the corrections are summed as if independent.
//! A sphere midway in a slit of half-width `l` moves along the walls with
//! `1 - 9/8 (a/l) + 1/4 (a/l)^3 - 1/8 (a/l)^5` of its free mobility, against Faxén's
//! `1 - 1.004 (a/l) + 0.418 (a/l)^3 + ...`; across them with
//! `1 - 9/4 (a/l) + (a/l)^3 - 1/4 (a/l)^5`, which vanishes at `a/l ~ 0.497` and is
//! negative in narrower slits (a mobility that is not positive definite; and a sphere
//! touching one wall has `1 - 3/4 - 9/8 x + ...` across, negative once the other wall
//! is within about `4.4 a` of its centre). A sphere whose own blocks are not positive
//! definite is refused ([`SlitError::NotPositive`]), never evaluated; a configuration
//! whose pairs alone make the mobility indefinite is left to the factorisation that
//! meets it (`docs/GEOMETRY.md`, "The slit").
//!
//! A centre within a radius of a wall is treated as above the single wall (lifted to
//! the contact height, its rows and columns damped by `h / a`), for each wall; a centre
//! on or past either plane is refused ([`ParticleError::BelowWall`]), and so is a slit
//! narrower than the sphere.

use crate::fault::ParticleError;
use crate::linalg::tri;
use crate::mobility::wall::{image_rot, image_tt, self_wall, self_wall_rot};
use crate::mobility::{
    Grand, Hydro, PairBlocks, add_spin_of, assemble_grand_of, pair_blocks, pair_tt, self_rr,
    self_tt,
};
use crate::parallel::{
    Blocks, Parallel, assemble_blocks, block_at, product_blocks, serial_product,
};
use crate::real::Real;

/// What the slit's blocks refuse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SlitError {
    /// A sphere's centre on or past a wall, nested spheres (the wall's errors).
    Particle(ParticleError),
    /// A sphere whose own `6 x 6` self block is not positive definite under
    /// superposition (too near both walls): its index.
    NotPositive {
        /// Index of the particle.
        particle: usize,
    },
}

/// The mirror `P = diag(1, 1, -1)` of `m`: `P m P`.
#[inline(always)]
fn mirror<T: Real>(m: T::M3) -> T::M3 {
    let p = T::m3_cols(
        T::v3(T::ONE, T::ZERO, T::ZERO),
        T::v3(T::ZERO, T::ONE, T::ZERO),
        T::v3(T::ZERO, T::ZERO, -T::ONE),
    );
    p * m * p
}

/// `diag(par, par, perp)`.
#[inline(always)]
fn diag<T: Real>(par: T, perp: T) -> T::M3 {
    let o = T::ZERO;
    T::m3_cols(T::v3(par, o, o), T::v3(o, par, o), T::v3(o, o, perp))
}

/// A sphere as the slit sees it: its centre (kept a radius clear of each wall), its
/// heights above the floor and below the ceiling there, and its damping `b`.
#[derive(Clone, Copy)]
pub(crate) struct Site<T: Real> {
    p: T::V3,
    h0: T,
    h1: T,
    b: T,
}

/// `(mu_par, mu_perp, rr_par, rr_perp, c)` of a lone sphere of radius `a` at heights
/// `h0`, `h1` from the walls: free space plus both walls' corrections; its `rt` block
/// is `c z x` (the floor's `c0` less the ceiling's mirrored `c1`).
fn self_terms<T: Real>(eta: T, a: T, h0: T, h1: T) -> [T; 5] {
    let ((p0, q0), (p1, q1), s) = (
        self_wall(eta, a, h0),
        self_wall(eta, a, h1),
        self_tt(eta, a),
    );
    let ((r0, w0, c0), (r1, w1, c1)) = (self_wall_rot(eta, a, h0), self_wall_rot(eta, a, h1));
    let r = self_rr(eta, a);
    [p0 + p1 - s, q0 + q1 - s, r0 + r1 - r, w0 + w1 - r, c0 - c1]
}

/// Sphere `i` at `p` of radius `a` between the walls.
#[inline(always)]
fn site<T: Real>(
    eta: T,
    (floor, ceiling): (T, T),
    a: T,
    p: T::V3,
    i: usize,
) -> Result<Site<T>, SlitError> {
    let [x, y, z] = T::xyz(p);
    let (h0, h1) = (z - floor, ceiling - z);
    if !(h0 > T::ZERO && h1 > T::ZERO && ceiling - floor >= a * T::TWO) {
        return Err(SlitError::Particle(ParticleError::BelowWall {
            particle: i,
        }));
    }
    let one = T::ONE;
    let b = (h0 / a).min(one) * (h1 / a).min(one);
    let s = match (h0 >= a, h1 >= a) {
        (true, true) => Site { p, h0, h1, b },
        (false, _) => Site {
            p: T::v3(x, y, floor + a),
            h0: a,
            h1: ceiling - floor - a,
            b,
        },
        (true, false) => Site {
            p: T::v3(x, y, ceiling - a),
            h0: ceiling - floor - a,
            h1: a,
            b,
        },
    };
    let [par, perp, rpar, _, c] = self_terms(eta, a, s.h0, s.h1);
    // The self block's `2 x 2` minors (`tt_par`, `rr_par` coupled by `c`) and `tt_perp`.
    if !(par > T::ZERO && perp > T::ZERO && par * rpar > c * c) {
        return Err(SlitError::NotPositive { particle: i });
    }
    Ok(s)
}

/// `mu_tt` and the grand mobility between the walls, block by block.
#[derive(Clone, Copy)]
struct Slit<'a, T: Real> {
    level: Hydro,
    eta: T,
    walls: (T, T),
    pos: &'a [T::V3],
    radius: &'a [T],
}

/// The radii the images are evaluated with at `level` (`None`: no pair images).
#[inline(always)]
fn image_radii<T: Real>(level: Hydro, ai: T, aj: T) -> Option<(T, T)> {
    match level {
        Hydro::FreeDraining => None,
        Hydro::Oseen => Some((T::ZERO, T::ZERO)),
        Hydro::Rpy => Some((ai, aj)),
    }
}

impl<T: Real> Blocks<T> for Slit<'_, T> {
    type Site = Site<T>;
    type Error = SlitError;
    #[inline(always)]
    fn site(&self, i: usize) -> Result<Site<T>, SlitError> {
        site(self.eta, self.walls, self.radius[i], self.pos[i], i)
    }
    #[inline(always)]
    fn diag(&self, i: usize, s: Site<T>) -> T::M3 {
        let [par, perp, ..] = self_terms(self.eta, self.radius[i], s.h0, s.h1);
        let b2 = s.b * s.b;
        diag::<T>(par * b2, perp * b2)
    }
    #[inline(always)]
    fn pair(&self, i: usize, si: Site<T>, j: usize, sj: Site<T>) -> Result<T::M3, SlitError> {
        let (ai, aj, eta) = (self.radius[i], self.radius[j], self.eta);
        let r = si.p - sj.p;
        let nested = SlitError::Particle(ParticleError::Nested { i: j, j: i });
        let free = pair_tt(self.level, eta, ai, aj, r).ok_or(nested)?;
        let Some((ri, rj)) = image_radii(self.level, ai, aj) else {
            return Ok(free);
        };
        let floor = image_tt(eta, ri, rj, r, si.h0 + sj.h0, sj.h0);
        let ceiling = mirror::<T>(image_tt(eta, ri, rj, r, si.h1 + sj.h1, sj.h1));
        Ok((free + floor + ceiling) * (si.b * sj.b))
    }
}

impl<T: Real> Grand<T> for Slit<'_, T> {
    #[inline(always)]
    fn self_rr(&self, i: usize, s: Site<T>) -> T::M3 {
        let [_, _, par, perp, _] = self_terms(self.eta, self.radius[i], s.h0, s.h1);
        let b2 = s.b * s.b;
        diag::<T>(par * b2, perp * b2)
    }
    #[inline(always)]
    fn self_rt(&self, i: usize, s: Site<T>) -> Option<T::M3> {
        let [.., c] = self_terms(self.eta, self.radius[i], s.h0, s.h1);
        Some(T::m3_cross(T::v3(T::ZERO, T::ZERO, T::ONE)) * (c * s.b * s.b))
    }
    fn pair_grand(
        &self,
        i: usize,
        si: Site<T>,
        j: usize,
        sj: Site<T>,
    ) -> Result<PairBlocks<T>, SlitError> {
        let (ai, aj, eta) = (self.radius[i], self.radius[j], self.eta);
        let r = si.p - sj.p;
        let nested = SlitError::Particle(ParticleError::Nested { i: j, j: i });
        let free = pair_blocks(self.level, eta, ai, aj, r).ok_or(nested)?;
        let Some((ri, rj)) = image_radii(self.level, ai, aj) else {
            return Ok(free);
        };
        let bb = si.b * sj.b;
        let tt = self.pair(i, si, j, sj)?;
        // The floor's images, then the ceiling's mirrored (`-P W P` for the couplings).
        let (z0, z1) = (si.h0 + sj.h0, si.h1 + sj.h1);
        let (rt_ij0, rr0) = image_rot(eta, rj, r, z0, sj.h0);
        let (rt_ji0, _) = image_rot(eta, ri, -r, z0, si.h0);
        let (rt_ij1, rr1) = image_rot(eta, rj, r, z1, sj.h1);
        let (rt_ji1, _) = image_rot(eta, ri, -r, z1, si.h1);
        Ok(PairBlocks {
            tt,
            rt_ij: (free.rt_ij + rt_ij0 - mirror::<T>(rt_ij1)) * bb,
            rt_ji: (free.rt_ji + rt_ji0 - mirror::<T>(rt_ji1)) * bb,
            rr: (free.rr + rr0 + mirror::<T>(rr1)) * bb,
        })
    }
}

impl<'a, T: Real> Slit<'a, T> {
    #[inline(always)]
    fn new(level: Hydro, eta: T, walls: (T, T), pos: &'a [T::V3], radius: &'a [T]) -> Self {
        Self {
            level,
            eta,
            walls,
            pos,
            radius,
        }
    }
}

/// The walls `(floor, ceiling)` and the level and viscosity a slit's blocks read.
pub type Walls<T> = (Hydro, T, (T, T));

/// Block `(p, q)` of `mu_tt` in the slit, in that orientation.
pub fn tt_block_at<T: Real>(
    (level, eta, walls): Walls<T>,
    pos: &[T::V3],
    radius: &[T],
    p: usize,
    q: usize,
) -> Result<T::M3, SlitError> {
    block_at(&Slit::new(level, eta, walls, pos, radius), true, p, q)
}

/// Assembles `mu_tt` in the slit (packed lower triangle, [`tri`]`(n)` blocks) in bands
/// through `par`.
pub fn assemble<T: Real>(
    par: &dyn Parallel,
    (level, eta, walls): Walls<T>,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), SlitError> {
    let src = Slit::new(level, eta, walls, pos, radius);
    let none = (&mut [][..], tri as fn(usize) -> usize);
    assemble_blocks(par, pos.len(), &src, out, none, |_, _, _, _| {})
}

/// `y = mu_tt x` in the slit without storing `mu_tt`, in the bands of
/// [`crate::parallel::product`] through `par` (`z`: their scratch): the bits of
/// [`assemble`] then the stored product.
pub fn free_product<T: Real>(
    par: &dyn Parallel,
    (level, eta, walls): Walls<T>,
    (pos, radius): (&[T::V3], &[T]),
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), SlitError> {
    let src = Slit::new(level, eta, walls, pos, radius);
    product_blocks(par, &src, &x[..pos.len()], y, z)
}

/// `y = mu_tt x` in the slit on one thread, in the order of [`assemble`] and
/// [`sym_matvec`](crate::linalg::sym_matvec).
pub fn tt_product<T: Real>(
    (level, eta, walls): Walls<T>,
    (pos, radius): (&[T::V3], &[T]),
    x: &[T::V3],
    y: &mut [T::V3],
) -> Result<(), SlitError> {
    serial_product(
        &Slit::new(level, eta, walls, pos, radius),
        &x[..pos.len()],
        y,
    )
}

/// The `2n x 2n` grand mobility in the slit (translations then rotations), packed as
/// [`assemble_grand`](crate::mobility::assemble_grand) stores it.
pub fn assemble_grand<T: Real>(
    (level, eta, walls): Walls<T>,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), SlitError> {
    assemble_grand_of(&Slit::new(level, eta, walls, pos, radius), pos.len(), out)
}

/// `out_i += sum_j rt_ij f_j` in the slit (self terms included).
pub fn add_spin<T: Real>(
    (level, eta, walls): Walls<T>,
    (pos, radius): (&[T::V3], &[T]),
    f: &[T::V3],
    out: &mut [T::V3],
) -> Result<(), SlitError> {
    add_spin_of(
        &Slit::new(level, eta, walls, pos, radius),
        pos.len(),
        f,
        out,
    )
}
