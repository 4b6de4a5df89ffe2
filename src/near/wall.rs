//! A sphere of radius `a` whose centre is at height `h > a` above a no-slip plane wall.
//!
//! Dimensionless resistance functions, `delta = h / a - 1` the gap in radii:
//! * perpendicular translation `X^A_w = F / (6 pi eta a U)`: Brenner's (1961) exact
//!   bispherical series, summed in closed form term by term; below `delta = 1e-3`
//!   Cox and Brenner's (1967) asymptote `1/delta + (1/5) ln(1/delta) + 0.9713`;
//! * rotation about the normal `X^C_w = T / (8 pi eta a^3 W)`: Jeffery's (1915) exact
//!   image series `sum_{n>=0} (sinh(alpha) / sinh((n + 1) alpha))^3`, `cosh(alpha) = h/a`;
//! * parallel translation `Y^A_w`, the coupling `Y^B_w = T / (8 pi eta a^2 U)` (equal to
//!   `F / (6 pi eta a^2 W)` times 3/4, by reciprocity) and rotation parallel to the wall
//!   `Y^C_w`: Goldman, Cox and Brenner's (1967) near-contact asymptotes for
//!   `delta <= DELTA_NEAR` and the method of reflections' series in `a / h` (Faxen; Goldman,
//!   Cox and Brenner 1967) for `delta >= DELTA_FAR`, joined in between by a cubic in
//!   `ln(delta)` matching both values and slopes (no exact values there: see docs/NEAR.md).
//!
//! The blocks, with `n` the wall's unit normal into the fluid:
//! `F = 6 pi eta a (X^A_w n n + Y^A_w (I - n n)) U + B^T W` and
//! `T = B U + 8 pi eta a^3 (X^C_w n n + Y^C_w (I - n n)) W` with
//! `B_ij = 8 pi eta a^2 Y^B_w eps_ijk n_k` (forces and torques on the fluid; `Y^B_w > 0`
//! turns a torque-free sphere in the rolling sense).

use super::NearError;
use super::axial::csch3_sum;
use crate::real::Real;

/// Below this gap the parallel functions are Goldman, Cox and Brenner's asymptotes.
pub const DELTA_NEAR: f64 = 0.05;
/// From this gap on the parallel functions are the reflection series.
pub const DELTA_FAR: f64 = 1.0;
/// Below this gap the perpendicular function is Cox and Brenner's asymptote.
pub const DELTA_BRENNER: f64 = 1e-3;

/// The five wall functions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallScalars<T> {
    /// Perpendicular translation.
    pub xa: T,
    /// Parallel translation.
    pub ya: T,
    /// Translation-rotation coupling.
    pub yb: T,
    /// Rotation about the normal.
    pub xc: T,
    /// Rotation about an axis parallel to the wall.
    pub yc: T,
}

/// Brenner's (1961) series for `cosh(alpha) = h / a`, each bracket in a form without
/// overflow: `(2 - 2 e^{-k a} + k sinh 2a + k^2 sinh^2 a) / (4 sinh^2(k a / 2) - k^2
/// sinh^2 a)` with `k = 2n + 1` (the series' `num / den - 1`).
fn brenner(alpha: f64) -> f64 {
    let sh = libm::sinh(alpha);
    let sh2 = libm::sinh(2.0 * alpha);
    let mut sum = 0.0;
    for n in 1..200_000u32 {
        let nf = n as f64;
        let k = 2.0 * nf + 1.0;
        let hk = libm::sinh(0.5 * k * alpha);
        let den = 4.0 * hk * hk - k * k * sh * sh;
        let num = 2.0 - 2.0 * libm::exp(-k * alpha) + k * sh2 + k * k * sh * sh;
        let term = nf * (nf + 1.0) / ((2.0 * nf - 1.0) * (2.0 * nf + 3.0)) * num / den;
        sum += term;
        if !(term > 1e-17 * sum) {
            break;
        }
    }
    4.0 / 3.0 * sh * sum
}

/// Perpendicular translation, `delta > 0`.
pub fn perpendicular(delta: f64) -> f64 {
    if delta < DELTA_BRENNER {
        return 1.0 / delta + 0.2 * libm::log(1.0 / delta) + 0.9713;
    }
    if delta > 1e3 {
        // Far away Brenner's terms overflow; the reflections' mobility 1 - 9/8 k + 1/2 k^3
        // (Lorentz; Brenner's series to O(k^4), below 1e-12 here) is exact enough.
        let k = 1.0 / (1.0 + delta);
        return 1.0 / (1.0 - 9.0 / 8.0 * k + 0.5 * k * k * k);
    }
    brenner(libm::acosh(1.0 + delta))
}

/// Rotation about the normal, `delta > 0`.
pub fn axial(delta: f64) -> f64 {
    let alpha = libm::acosh(1.0 + delta);
    csch3_sum(libm::sinh(alpha), alpha, alpha, 0)
}

/// Goldman, Cox and Brenner's near-contact forms `(Y^A, Y^B, Y^C)` and their slopes in
/// `ln(delta)`.
fn parallel_near(delta: f64) -> ([f64; 3], [f64; 3]) {
    let l = libm::log(1.0 / delta);
    (
        [8.0 / 15.0 * l + 0.9588, 0.1 * l - 0.1895, 0.4 * l + 0.3817],
        [-8.0 / 15.0, -0.1, -0.4],
    )
}

/// The reflection series `(Y^A, Y^B, Y^C)` in `k = a / h` and their slopes in `ln(delta)`.
fn parallel_far(delta: f64) -> ([f64; 3], [f64; 3]) {
    let k = 1.0 / (1.0 + delta);
    let (k3, k4) = (k * k * k, k * k * k * k);
    // Mobilities: parallel translation (Faxen), rotation, and the rotation a force gives.
    let mt = 1.0 - 9.0 / 16.0 * k + k3 / 8.0 - 45.0 / 256.0 * k4 - k4 * k / 16.0;
    let mr = 1.0 - 5.0 / 16.0 * k3;
    let mc = 3.0 / 32.0 * k4;
    // d/dk of each, then d/d ln(delta) = -k (1 - k) d/dk.
    let dmt = -9.0 / 16.0 + 3.0 * k * k / 8.0 - 45.0 / 64.0 * k3 - 5.0 * k4 / 16.0;
    let dmr = -15.0 / 16.0 * k * k;
    let dmc = 3.0 / 8.0 * k3;
    // Invert the 2x2 mobility [[mt, 4/3 mc], [mc, mr]] (reciprocity) in the resistance normalisation.
    let det = mt * mr - 4.0 / 3.0 * mc * mc;
    let v = [mr / det, mc / det, mt / det];
    let ddet = dmt * mr + mt * dmr - 8.0 / 3.0 * mc * dmc;
    let dv = [
        (dmr * det - mr * ddet) / (det * det),
        (dmc * det - mc * ddet) / (det * det),
        (dmt * det - mt * ddet) / (det * det),
    ];
    let chain = -k * (1.0 - k);
    (v, dv.map(|d| d * chain))
}

/// The parallel functions `(Y^A, Y^B, Y^C)`, `delta > 0`.
pub fn parallel(delta: f64) -> [f64; 3] {
    if delta <= DELTA_NEAR {
        return parallel_near(delta).0;
    }
    if delta >= DELTA_FAR {
        return parallel_far(delta).0;
    }
    let (x0, x1) = (libm::log(DELTA_NEAR), libm::log(DELTA_FAR));
    let h = x1 - x0;
    let t = (libm::log(delta) - x0) / h;
    let (v0, d0) = parallel_near(DELTA_NEAR);
    let (v1, d1) = parallel_far(DELTA_FAR);
    let (t2, t3) = (t * t, t * t * t);
    let (h00, h10, h01, h11) = (
        2.0 * t3 - 3.0 * t2 + 1.0,
        t3 - 2.0 * t2 + t,
        -2.0 * t3 + 3.0 * t2,
        t3 - t2,
    );
    core::array::from_fn(|i| h00 * v0[i] + h10 * h * d0[i] + h01 * v1[i] + h11 * h * d1[i])
}

/// The wall functions of a sphere of radius `a` with its centre at height `h`.
pub fn wall_scalars<T: Real>(a: T, h: T) -> Result<WallScalars<T>, NearError> {
    let (a, h) = (a.to_f64(), h.to_f64());
    if !(a.is_finite() && a > 0.0 && h.is_finite()) {
        return Err(NearError::NotPositive);
    }
    let delta = (h - a) / a;
    if !(delta > 0.0) {
        return Err(NearError::Contact);
    }
    let [ya, yb, yc] = parallel(delta);
    let c = T::from_f64;
    Ok(WallScalars {
        xa: c(perpendicular(delta)),
        ya: c(ya),
        yb: c(yb),
        xc: c(axial(delta)),
        yc: c(yc),
    })
}
