//! Far-field hydrodynamics: the polydisperse Rotne-Prager-Yamakawa grand mobility
//! (Zuk, Wajnryb, Mizerski & Szymczak, J. Fluid Mech. 741 R5, 2014) and two cheaper
//! levels (Oseen, free-draining).
//!
//! Blocks follow `U_i = sum_j (tt_ij F_j + tr_ij T_j)`, `W_i = sum_j (rt_ij F_j + rr_ij T_j)`
//! with `r = r_i - r_j`, `s = |r|`, `e = r / s`. Storage is caller-owned: the packed
//! lower triangle of 3x3 blocks ([`crate::linalg`]), `n x n` for `tt` alone or `2n x 2n`
//! for the grand mobility (block rows `0..n` translations, `n..2n` rotations, matching
//! the ordering of the reference data). `out` must hold at least `tri(n)` (or
//! `tri(2n)`) blocks: its length is the caller's contract, as for any slice API.

use crate::error::ParticleError;
use crate::linalg::tri;
use crate::real::Real;

#[cfg(feature = "fast-free")]
pub mod free_fast;
#[cfg(feature = "periodic")]
pub mod periodic;
#[cfg(feature = "pse")]
pub mod pse;
#[cfg(feature = "periodic")]
pub mod sums;
pub mod wall;

/// How much hydrodynamics to model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Hydro {
    /// Self terms only (Stokes drag on each sphere, no interactions).
    FreeDraining,
    /// Point-force (Oseen) interactions: `(I + e e) / (8 pi eta s)`. Not positive
    /// definite when spheres come close: a documented failure case.
    Oseen,
    /// Rotne-Prager-Yamakawa, far and overlapping branches (default).
    #[default]
    Rpy,
}

/// The 3x3 blocks of one pair's mobility.
#[derive(Clone, Copy, Debug)]
pub struct PairBlocks<T: Real> {
    /// Translation of `i` from force on `j` (`tt_ij = tt_ji`).
    pub tt: T::M3,
    /// Rotation of `i` from force on `j`.
    pub rt_ij: T::M3,
    /// Rotation of `j` from force on `i` (differs from `-rt_ij` for unequal
    /// overlapping spheres).
    pub rt_ji: T::M3,
    /// Rotation from torque (`rr_ij = rr_ji`).
    pub rr: T::M3,
}

/// `1/(6 pi eta a)`: Stokes' translational mobility of a lone sphere.
pub fn self_tt<T: Real>(eta: T, a: T) -> T {
    T::ONE / (T::from_f64(6.0) * T::PI * eta * a)
}

/// `1/(8 pi eta a^3)`: rotational mobility of a lone sphere.
pub fn self_rr<T: Real>(eta: T, a: T) -> T {
    T::ONE / (T::from_f64(8.0) * T::PI * eta * a * a * a)
}

/// Geometry of a pair, computed once: `s^2`, `s`, `1/s`, `e = r/s` and `e e^T`
/// (formed before any scaling, so the blocks built from it are exactly symmetric).
struct Geometry<T: Real> {
    s2: T,
    s: T,
    inv_s: T,
    e: T::V3,
    ee: T::M3,
}

impl<T: Real> Geometry<T> {
    /// `None` when one sphere lies inside the other (`s <= |a_i - a_j|`).
    #[inline(always)]
    fn new(ai: T, aj: T, r: T::V3) -> Option<Self> {
        let s2 = T::norm2(r);
        let dif = ai - aj;
        if s2 <= dif * dif {
            return None;
        }
        Some(Self::from_roots(r, s2, s2.root_and_inverse()))
    }

    /// From `s2 = |r|^2` and `s2.root_and_inverse()`.
    #[inline(always)]
    fn from_roots(r: T::V3, s2: T, (s, inv_s): (T, T)) -> Self {
        let e = r * inv_s;
        Self {
            s2,
            s,
            inv_s,
            e,
            ee: T::outer(e, e),
        }
    }
}

/// Translation-translation block for the pair `(i, j)`, `i != j`.
///
/// `None` when one sphere lies inside the other, at every level (no valid
/// configuration). Blocks are exactly symmetric.
#[inline(always)]
pub fn pair_tt<T: Real>(level: Hydro, eta: T, ai: T, aj: T, r: T::V3) -> Option<T::M3> {
    if level == Hydro::FreeDraining {
        let dif = ai - aj;
        return (T::norm2(r) > dif * dif).then_some(T::M3_ZERO);
    }
    Geometry::new(ai, aj, r).map(|g| tt_block(level, eta, ai, aj, &g))
}

/// [`pair_tt`] in two stages, for loops that take every square root of a run of pairs
/// before building their blocks (the roots and divisions then overlap instead of forming
/// one latency chain per pair): stage one, `|r|^2`, or `None` where [`pair_tt`] is
/// `None`.
#[inline(always)]
pub(crate) fn pair_norm2<T: Real>(level: Hydro, ai: T, aj: T, r: T::V3) -> Option<T> {
    let (s2, dif) = (T::norm2(r), ai - aj);
    // As in `pair_tt`: `>` for free draining, not `<=` otherwise (NaN passes there).
    let nested = s2 <= dif * dif;
    let apart = if level == Hydro::FreeDraining {
        s2 > dif * dif
    } else {
        !nested
    };
    apart.then_some(s2)
}

/// Stage two of [`pair_norm2`]: the block of [`pair_tt`], bit for bit, from `s2` and
/// `s2.root_and_inverse()`.
#[inline(always)]
pub(crate) fn pair_tt_from<T: Real>(
    level: Hydro,
    eta: T,
    ai: T,
    aj: T,
    r: T::V3,
    s2: T,
    roots: (T, T),
) -> T::M3 {
    if level == Hydro::FreeDraining {
        return T::M3_ZERO;
    }
    tt_block(level, eta, ai, aj, &Geometry::from_roots(r, s2, roots))
}

/// The `tt` block of an interacting level (Oseen or RPY) from the pair geometry.
#[inline(always)]
fn tt_block<T: Real>(level: Hydro, eta: T, ai: T, aj: T, g: &Geometry<T>) -> T::M3 {
    let (s2, s, ee) = (g.s2, g.s, g.ee);
    // 1 / (8 pi eta s): the constant folds out of the assembly loop once inlined.
    let c = g.inv_s * (T::ONE / (T::from_f64(8.0) * T::PI * eta));
    if level == Hydro::Oseen {
        return T::m3_add_diag(ee * c, c);
    }
    let sum = ai + aj;
    let dif = ai - aj;
    if s > sum {
        let q = (ai * ai + aj * aj) * (g.inv_s * g.inv_s);
        let third = T::ONE / T::from_f64(3.0);
        T::m3_add_diag(ee * (c * (T::ONE - q)), c * (T::ONE + q * third))
    } else {
        // Overlapping branch (Zuk et al. 2014, eq. 2.7): stays positive definite.
        let s3 = s2 * s;
        let k = T::ONE / (T::from_f64(6.0) * T::PI * eta * ai * aj * T::from_f64(32.0) * s3);
        let p = dif * dif + T::from_f64(3.0) * s2;
        let iso = T::from_f64(16.0) * s3 * sum - p * p;
        let q = dif * dif - s2;
        let aniso = T::from_f64(3.0) * q * q;
        T::m3_add_diag(ee * (k * aniso), k * iso)
    }
}

/// All blocks for the pair `(i, j)`, `i != j` (rotation couplings included).
pub fn pair_blocks<T: Real>(level: Hydro, eta: T, ai: T, aj: T, r: T::V3) -> Option<PairBlocks<T>> {
    if level == Hydro::FreeDraining {
        return pair_tt(level, eta, ai, aj, r).map(|tt| PairBlocks {
            tt,
            rt_ij: T::M3_ZERO,
            rt_ji: T::M3_ZERO,
            rr: T::M3_ZERO,
        });
    }
    let g = Geometry::new(ai, aj, r)?;
    let tt = tt_block(level, eta, ai, aj, &g);
    let (s2, s, ee) = (g.s2, g.s, g.ee);
    let three = T::from_f64(3.0);
    let pi8 = T::from_f64(8.0) * T::PI * eta;
    // rt_ij F = c_ij (F x e) = -c_ij [e]x F; rt_ji uses -e and the swapped radii.
    let cross = T::m3_cross(g.e);
    let far = level == Hydro::Oseen || s > ai + aj;
    let rt_ij = cross * (-rt_coefficient(far, eta, ai, aj, s));
    let rt_ji = cross * rt_coefficient(far, eta, aj, ai, s);
    if far {
        let rr = (ee * three - T::M3_IDENTITY) * (T::ONE / (T::TWO * pi8 * s2 * s));
        return Some(PairBlocks {
            tt,
            rt_ij,
            rt_ji,
            rr,
        });
    }
    // Overlapping branch (Zuk et al. 2014).
    let s3 = s2 * s;
    let (ai2, aj2) = (ai * ai, aj * aj);
    let dif = ai - aj;
    let dif2 = dif * dif;
    let w = ai2 + T::from_f64(4.0) * ai * aj + aj2;
    let iso = T::from_f64(5.0) * s3 * s3 - T::from_f64(27.0) * s2 * s2 * (ai2 + aj2)
        + T::from_f64(32.0) * s3 * (ai2 * ai + aj2 * aj)
        - T::from_f64(9.0) * s2 * (ai2 - aj2) * (ai2 - aj2)
        - dif2 * dif2 * w;
    let q = dif2 - s2;
    let aniso = three * q * q * (w - s2);
    let krr = T::ONE / (pi8 * ai2 * ai * aj2 * aj * T::from_f64(64.0) * s3);
    let rr = T::m3_diag(krr * iso) + ee * (krr * aniso);
    Some(PairBlocks {
        tt,
        rt_ij,
        rt_ji,
        rr,
    })
}

/// Scalar `c` in `rt_ij F = c (F x e_ij)`, `e_ij = (r_i - r_j)/s`.
fn rt_coefficient<T: Real>(far: bool, eta: T, ai: T, aj: T, s: T) -> T {
    let pi16 = T::from_f64(16.0) * T::PI * eta;
    if far {
        return T::TWO / (pi16 * s * s);
    }
    // Continuous with the far form at s = a_i + a_j (both give 1 / (8 pi eta s^2)).
    let g = ai - aj + s;
    let h = ai - s;
    let poly = g * g * (aj * aj + T::TWO * aj * (ai + s) - T::from_f64(3.0) * h * h);
    poly / (pi16 * ai * ai * ai * aj * T::from_f64(8.0) * s * s)
}

/// `y = mu_tt x` without storing `mu_tt`: each pair block is evaluated where it is
/// used, in the orientation and summation order of [`assemble_tt`] followed by
/// [`sym_matvec`](crate::linalg::sym_matvec), so the result is bit-identical to the
/// stored path below [`BANDED_MIN`](crate::parallel::BANDED_MIN) rows (from there on the
/// stored path sums in bands, [`crate::parallel`]; this one does not, so the two agree to
/// rounding), at the cost of re-evaluating the pairs (storage `O(N)` instead of
/// `O(N^2)`). Nested spheres are an error, as in assembly.
pub fn tt_product<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
) -> Result<(), ParticleError> {
    let n = pos.len();
    for i in 0..n {
        y[i] = T::m3_diag(self_tt(eta, radius[i])) * x[i];
    }
    for i in 0..n {
        let mut acc = T::V3_ZERO;
        for j in 0..i {
            let b = pair_tt(level, eta, radius[i], radius[j], pos[i] - pos[j])
                .ok_or(ParticleError::Nested { i: j, j: i })?;
            acc += b * x[j];
            y[j] += T::m3_tmul(b, x[i]);
        }
        y[i] += acc;
    }
    Ok(())
}

/// Block `(p, q)` of `mu_tt` as [`assemble_tt`] stores it (the pair evaluated from the
/// higher index), `None` for nested spheres.
#[inline]
pub fn tt_block_at<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    p: usize,
    q: usize,
) -> Option<T::M3> {
    let (i, j) = if p >= q { (p, q) } else { (q, p) };
    if i == j {
        return Some(T::m3_diag(self_tt(eta, radius[i])));
    }
    pair_tt(level, eta, radius[i], radius[j], pos[i] - pos[j])
}

/// Assembles the `n x n` translational mobility `mu_tt`, packed lower triangle
/// ([`tri`]`(n)` blocks into `out`; symmetric by construction: each pair is evaluated once).
pub fn assemble_tt<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [impl crate::linalg::Block<T>],
) -> Result<(), ParticleError> {
    crate::parallel::assemble(&crate::parallel::Serial, level, eta, pos, radius, out)
}

/// Assembles the `2n x 2n` grand mobility `[[tt, tr], [rt, rr]]`, packed lower triangle
/// (`tri(2n)` blocks; the upper blocks `tr_ij = rt_ji^T` follow by symmetry).
pub fn assemble_grand<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), ParticleError> {
    let n = pos.len();
    for i in 0..n {
        let a = radius[i];
        let (ti, ri) = (tri(i), tri(n + i));
        out[ti + i] = T::m3_diag(self_tt(eta, a));
        out[ri + n + i] = T::m3_diag(self_rr(eta, a));
        out[ri + i] = T::M3_ZERO;
        for j in 0..i {
            let b = pair_blocks(level, eta, a, radius[j], pos[i] - pos[j])
                .ok_or(ParticleError::Nested { i: j, j: i })?;
            let rj = tri(n + j);
            out[ti + j] = b.tt;
            out[ri + n + j] = b.rr;
            out[ri + j] = b.rt_ij;
            out[rj + i] = b.rt_ji;
        }
    }
    Ok(())
}
