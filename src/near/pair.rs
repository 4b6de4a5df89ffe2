//! The ten scalar resistance functions of a pair and its 12x12 resistance matrix.

use super::lubrication::Func;
use super::{LAMBDA_MAX, LAMBDA_MIN, NearError, axial, series, tables, value};
use crate::real::Real;

/// Jeffrey and Onishi's (1984) ten scalar resistance functions of sphere 1 (radius `a1`)
/// and sphere 2 (radius `a2`), dimensionless as in [`super`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scalars<T> {
    /// `X^A_11`.
    pub xa11: T,
    /// `X^A_12`.
    pub xa12: T,
    /// `Y^A_11`.
    pub ya11: T,
    /// `Y^A_12`.
    pub ya12: T,
    /// `Y^B_11`.
    pub yb11: T,
    /// `Y^B_12`.
    pub yb12: T,
    /// `X^C_11`.
    pub xc11: T,
    /// `X^C_12`.
    pub xc12: T,
    /// `Y^C_11`.
    pub yc11: T,
    /// `Y^C_12`.
    pub yc12: T,
}

fn check(a1: f64, a2: f64, r: f64) -> Result<f64, NearError> {
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !(ok(a1) && ok(a2) && ok(r)) {
        return Err(NearError::NotPositive);
    }
    let l = a2 / a1;
    if !(LAMBDA_MIN * (1.0 - 1e-12)..=LAMBDA_MAX * (1.0 + 1e-12)).contains(&l) {
        return Err(NearError::SizeRatio);
    }
    if !(r > a1 + a2) {
        return Err(NearError::Contact);
    }
    Ok(l.clamp(LAMBDA_MIN, LAMBDA_MAX))
}

fn scalars_f64(a1: f64, a2: f64, r: f64) -> Result<Scalars<f64>, NearError> {
    let l = check(a1, a2, r)?;
    let s = 2.0 * r / (a1 + a2);
    // Far pairs: the eight series side by side ([`series::far_all`], the same bits).
    let all = (s - 2.0 >= tables::XI_MAX).then(|| series::far_all(l, 2.0 / s));
    let v = |f: Func| all.map_or_else(|| value(f, l, s), |a| a[f as usize]);
    let (xc11, xc12) = axial::xc(a1, a2, r);
    Ok(Scalars {
        xa11: v(Func::X11A),
        xa12: v(Func::X12A),
        ya11: v(Func::Y11A),
        ya12: v(Func::Y12A),
        yb11: v(Func::Y11B),
        yb12: v(Func::Y12B),
        xc11,
        xc12,
        yc11: v(Func::Y11C),
        yc12: v(Func::Y12C),
    })
}

/// The ten functions for radii `a1`, `a2` at centre distance `r`.
pub fn scalars<T: Real>(a1: T, a2: T, r: T) -> Result<Scalars<T>, NearError> {
    let s = scalars_f64(a1.to_f64(), a2.to_f64(), r.to_f64())?;
    let c = T::from_f64;
    Ok(Scalars {
        xa11: c(s.xa11),
        xa12: c(s.xa12),
        ya11: c(s.ya11),
        ya12: c(s.ya12),
        yb11: c(s.yb11),
        yb12: c(s.yb12),
        xc11: c(s.xc11),
        xc12: c(s.xc12),
        yc11: c(s.yc11),
        yc12: c(s.yc12),
    })
}

/// The resistance of a pair: `(F1, F2, T1, T2) = r (U1, U2, W1, W2)`, `r[row][col]` 3x3
/// blocks, forces and torques exerted by the spheres on the fluid.
#[derive(Clone, Copy, Debug)]
pub struct PairResistance<T: Real> {
    /// Blocks, rows and columns ordered sphere 1 translation, sphere 2 translation,
    /// sphere 1 rotation, sphere 2 rotation.
    pub r: [[T::M3; 4]; 4],
}

/// A 3x3 block in `f64`, row-major.
pub(crate) type M = [[f64; 3]; 3];

/// `x d d + y (I - d d)`.
fn xy(x: f64, y: f64, d: [f64; 3]) -> M {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let dd = d[i] * d[j];
            m[i][j] = x * dd + y * (if i == j { 1.0 } else { 0.0 } - dd);
        }
    }
    m
}

/// `y eps_ijk d_k`.
fn eps(y: f64, d: [f64; 3]) -> M {
    [
        [0.0, y * d[2], -y * d[1]],
        [-y * d[2], 0.0, y * d[0]],
        [y * d[1], -y * d[0], 0.0],
    ]
}

fn transpose(m: M) -> M {
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = m[j][i];
        }
    }
    t
}

/// Sphere 1's blocks `(A11, A12, B11, B12, C11, C12)`, `d` the unit vector from 1 to 2.
fn half(eta: f64, a1: f64, a2: f64, d: [f64; 3], s: &Scalars<f64>) -> [M; 6] {
    use core::f64::consts::PI;
    let sum = a1 + a2;
    let scale = |m: M, k: f64| m.map(|row| row.map(|v| v * k));
    [
        scale(xy(s.xa11, s.ya11, d), 6.0 * PI * eta * a1),
        scale(xy(s.xa12, s.ya12, d), 3.0 * PI * eta * sum),
        scale(eps(s.yb11, d), 4.0 * PI * eta * a1 * a1),
        scale(eps(s.yb12, d), PI * eta * sum * sum),
        scale(xy(s.xc11, s.yc11, d), 8.0 * PI * eta * a1 * a1 * a1),
        scale(xy(s.xc12, s.yc12, d), PI * eta * sum * sum * sum),
    ]
}

/// A 3x3 block of `f64` as the caller's matrix type.
pub(crate) fn to_m3<T: Real>(m: M) -> T::M3 {
    let col = |j: usize| {
        T::v3(
            T::from_f64(m[0][j]),
            T::from_f64(m[1][j]),
            T::from_f64(m[2][j]),
        )
    };
    T::m3_cols(col(0), col(1), col(2))
}

/// [`pair_resistance`] in `f64` blocks.
pub(crate) fn resistance_f64(
    eta: f64,
    a1: f64,
    a2: f64,
    d: [f64; 3],
) -> Result<[[M; 4]; 4], NearError> {
    let [x, y, z] = d;
    let r = libm::sqrt(x * x + y * y + z * z);
    if !(eta.is_finite() && eta > 0.0) {
        return Err(NearError::NotPositive);
    }
    let s1 = scalars_f64(a1, a2, r)?;
    let s2 = scalars_f64(a2, a1, r)?;
    let e = [x / r, y / r, z / r];
    let [a11, a12, b11, b12, c11, c12] = half(eta, a1, a2, e, &s1);
    let [a22, a21, b22, b21, c22, c21] = half(eta, a2, a1, e.map(|v| -v), &s2);
    let t = transpose;
    Ok([
        [a11, a12, t(b11), t(b21)],
        [a21, a22, t(b12), t(b22)],
        [b11, b12, c11, c12],
        [b21, b22, c21, c22],
    ])
}

/// The exact two-sphere resistance of spheres of radii `a1` and `a2` in a fluid of
/// viscosity `eta`, sphere 2 at `d` from sphere 1 (any length above `a1 + a2`).
pub fn pair_resistance<T: Real>(
    eta: T,
    a1: T,
    a2: T,
    d: T::V3,
) -> Result<PairResistance<T>, NearError> {
    let d = T::xyz(d).map(T::to_f64);
    let b = resistance_f64(eta.to_f64(), a1.to_f64(), a2.to_f64(), d)?;
    Ok(PairResistance {
        r: b.map(|row| row.map(to_m3::<T>)),
    })
}
