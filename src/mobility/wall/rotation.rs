//! The wall's rotation blocks (`docs/WALL.md`, "Rotation"): the grand mobility above
//! the wall and the spins of torque-free spheres.
//!
//! `rt_ij = 1/2 curl_x (1 + a_j^2/6 lap_y) G(x, y)` and `rr_ij = 1/4 curl_x curl_y G`
//! at `x = r_i`, `y = r_j` (Faxén's laws for rotation), `G` Blake's Green's function:
//! the free-space RPY blocks plus image blocks given in the frame
//! `(p, q, z)`, `p` the wall-parallel direction of `R` (any, when `R` is normal), `q =
//! z x p`, then rotated to the axes ([`image_rot`]).

use super::{Lifted, Wall};
use crate::fault::ParticleError;
use crate::mobility::{
    Grand, Hydro, PairBlocks, add_spin_of, assemble_grand_of, pair_blocks, self_rr, self_tt,
};
use crate::real::Real;

/// The image's rotation blocks `(rt_ij, rr_ij)` for the source radius `aj`, `r = r_i -
/// r_j` (its wall-parallel part), `rz = h_i + h_j` and the source height `hj`
/// (`docs/WALL.md`, eq. WR). Zero radius gives the point force's image.
#[inline(always)]
pub fn image_rot<T: Real>(eta: T, aj: T, r: T::V3, rz: T, hj: T) -> (T::M3, T::M3) {
    let c = |v: f64| T::from_f64(v);
    let [rx, ry, _] = T::xyz(r);
    let rho2 = rx * rx + ry * ry;
    let (rho, cs, sn) = if rho2 > T::ZERO {
        let (rho, inv) = rho2.root_and_inverse();
        (rho, rx * inv, ry * inv)
    } else {
        (T::ZERO, T::ONE, T::ZERO)
    };
    let (_, u) = (rho2 + rz * rz).root_and_inverse();
    let (ez, er, t, b) = (rz * u, rho * u, hj * u, aj * aj * u * u);
    let ez2 = ez * ez;
    let k = T::ONE / (c(8.0) * T::PI * eta);
    let (u2, u3) = (u * u * k, u * u * u * k);
    let o = T::ZERO;
    let rt01 = u2 * (-ez + T::TWO * t - T::TWO * ez * b);
    let rt10 = u2 * (ez + t * (c(4.0) - c(6.0) * ez2) + b * ez * (c(10.0) * ez2 - c(8.0)));
    let rt12 = -er * u2 * (T::ONE + c(6.0) * ez * t + b * (T::TWO - c(10.0) * ez2));
    let rt21 = er * u2;
    let rr00 = -(T::TWO + c(3.0) * ez2) * T::HALF * u3;
    let rr11 = -(c(12.0) * ez2 - c(7.0)) * T::HALF * u3;
    let rr22 = -(c(3.0) * ez2 - T::ONE) * T::HALF * u3;
    let rr20 = c(1.5) * ez * er * u3;
    let rt0 = T::m3_cols(T::v3(o, rt10, o), T::v3(rt01, o, rt21), T::v3(o, rt12, o));
    let rr0 = T::m3_cols(
        T::v3(rr00, o, rr20),
        T::v3(o, rr11, o),
        T::v3(-rr20, o, rr22),
    );
    // E = [p q z]: blocks E M0 E^T.
    let e = T::m3_cols(T::v3(cs, sn, o), T::v3(-sn, cs, o), T::v3(o, o, T::ONE));
    let et = T::transpose(e);
    (e * rt0 * et, e * rr0 * et)
}

/// `(rr_par, rr_perp, c)` of a lone sphere of radius `a` at height `h`: `rr_ii =
/// diag(rr_par, rr_par, rr_perp)`, `rr_par = (1 - 5/16 x^3) / (8 pi eta a^3)`, `rr_perp =
/// (1 - 1/8 x^3) / (8 pi eta a^3)`, and `rt_ii F = c z x F`, `c = 3/32 x^4 / (6 pi eta
/// a^2)`, `x = a / h`.
pub fn self_wall_rot<T: Real>(eta: T, a: T, h: T) -> (T, T, T) {
    let c = |v: f64| T::from_f64(v);
    let x = a / h;
    let x3 = x * x * x;
    let r = self_rr(eta, a);
    let par = r * (T::ONE - c(5.0 / 16.0) * x3);
    let perp = r * (T::ONE - c(0.125) * x3);
    (par, perp, self_tt(eta, a) / a * c(3.0 / 32.0) * x3 * x)
}

/// The self rotation blocks `(rr_ii, rt_ii)` (damped by `b^2`).
fn self_rot<T: Real>(eta: T, a: T, s: Lifted<T>) -> (T::M3, T::M3) {
    let (par, perp, c) = self_wall_rot(eta, a, s.h);
    let b2 = s.b * s.b;
    let (par, perp) = (par * b2, perp * b2);
    let o = T::ZERO;
    let rr = T::m3_cols(T::v3(par, o, o), T::v3(o, par, o), T::v3(o, o, perp));
    let rt = T::m3_cross(T::v3(o, o, T::ONE)) * (c * b2);
    (rr, rt)
}

/// All blocks of the pair `(i, j)` above the wall (free space plus images, damped);
/// `None` for nested spheres. Free draining: no pair blocks.
fn pair_grand<T: Real>(
    level: Hydro,
    eta: T,
    ai: T,
    aj: T,
    si: Lifted<T>,
    sj: Lifted<T>,
) -> Option<PairBlocks<T>> {
    let r = si.p - sj.p;
    let free = pair_blocks(level, eta, ai, aj, r)?;
    let (ri, rj) = match level {
        Hydro::FreeDraining => return Some(free),
        Hydro::Oseen => (T::ZERO, T::ZERO),
        Hydro::Rpy => (ai, aj),
    };
    let (rz, bb) = (si.h + sj.h, si.b * sj.b);
    let tt = free.tt + super::image_tt(eta, ri, rj, r, rz, sj.h);
    let (rt_ij, rr) = image_rot(eta, rj, r, rz, sj.h);
    let (rt_ji, _) = image_rot(eta, ri, -r, rz, si.h);
    Some(PairBlocks {
        tt: tt * bb,
        rt_ij: (free.rt_ij + rt_ij) * bb,
        rt_ji: (free.rt_ji + rt_ji) * bb,
        rr: (free.rr + rr) * bb,
    })
}

/// Assembles the `2n x 2n` grand mobility above the wall at `height`, packed as
/// [`assemble_grand`](crate::mobility::assemble_grand) stores it (`tri(2n)` blocks; the
/// rotation-translation self blocks `rt_ii` are not zero near a wall).
pub fn assemble_grand<T: Real>(
    level: Hydro,
    eta: T,
    height: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), ParticleError> {
    let src = Wall::new(level, eta, height, pos, radius);
    assemble_grand_of(&src, pos.len(), out)
}

/// `out_i += sum_j rt_ij f_j` above the wall (self terms included): the spins of
/// torque-free spheres under the forces `f`.
pub fn add_spin<T: Real>(
    level: Hydro,
    eta: T,
    height: T,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    out: &mut [T::V3],
) -> Result<(), ParticleError> {
    let src = Wall::new(level, eta, height, pos, radius);
    add_spin_of(&src, pos.len(), f, out)
}

/// The wall's rotation blocks: its self blocks damped as its translational ones.
impl<T: Real> Grand<T> for Wall<'_, T> {
    #[inline(always)]
    fn self_rr(&self, i: usize, si: Lifted<T>) -> T::M3 {
        self_rot(self.eta, self.radius[i], si).0
    }
    #[inline(always)]
    fn self_rt(&self, i: usize, si: Lifted<T>) -> Option<T::M3> {
        Some(self_rot(self.eta, self.radius[i], si).1)
    }
    #[inline(always)]
    fn pair_grand(
        &self,
        i: usize,
        si: Lifted<T>,
        j: usize,
        sj: Lifted<T>,
    ) -> Result<PairBlocks<T>, ParticleError> {
        let (ai, aj) = (self.radius[i], self.radius[j]);
        pair_grand(self.level, self.eta, ai, aj, si, sj).ok_or(ParticleError::Nested { i: j, j: i })
    }
}
