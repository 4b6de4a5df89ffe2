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
//!   `Y^C_w`: the exact bispherical solutions (O'Neill 1964; Dean and O'Neill 1963),
//!   tabulated by `tools/near-gen` at gaps `1e-5 <= delta <= 10^1.7` (about 50) and read
//!   with cubic Lagrange interpolation in `log10(delta)`; below the table the
//!   near-contact form `c ln(1/delta) + const` (Goldman, Cox and Brenner 1967, their
//!   slopes `c`, the constant from the table's first node), above it the method of
//!   reflections' series in `a / h` (Faxen; Goldman, Cox and Brenner 1967) plus its
//!   fading error at the last node (see docs/NEAR.md for the accuracy).
//!
//! The blocks, with `n` the wall's unit normal into the fluid:
//! `F = 6 pi eta a (X^A_w n n + Y^A_w (I - n n)) U + B^T W` and
//! `T = B U + 8 pi eta a^3 (X^C_w n n + Y^C_w (I - n n)) W` with
//! `B_ij = 8 pi eta a^2 Y^B_w eps_ijk n_k` (forces and torques on the fluid; `Y^B_w > 0`
//! turns a torque-free sphere in the rolling sense).

use super::NearError;
use super::axial::csch3_sum;
use super::table::stencil;
use super::wall_table::{W_N, W_U_MIN, W_U_STEP, WALL};
use crate::real::Real;

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

/// Leading coefficients of `ln(1/delta)` near contact `(Y^A, Y^B, Y^C)` (Goldman, Cox
/// and Brenner 1967; O'Neill and Stewartson 1967).
const NEAR_SLOPE: [f64; 3] = [8.0 / 15.0, 0.1, 0.4];

/// The reflection series `(Y^A, Y^B, Y^C)` in `k = a / h`.
fn parallel_far(delta: f64) -> [f64; 3] {
    let k = 1.0 / (1.0 + delta);
    let (k3, k4) = (k * k * k, k * k * k * k);
    // Mobilities: parallel translation (Faxen), rotation, and the rotation a force gives.
    let mt = 1.0 - 9.0 / 16.0 * k + k3 / 8.0 - 45.0 / 256.0 * k4 - k4 * k / 16.0;
    let mr = 1.0 - 5.0 / 16.0 * k3;
    let mc = 3.0 / 32.0 * k4;
    // Invert the 2x2 mobility [[mt, 4/3 mc], [mc, mr]] (reciprocity) in the resistance normalisation.
    let det = mt * mr - 4.0 / 3.0 * mc * mc;
    [mr / det, mc / det, mt / det]
}

/// `log10` of the table's last gap.
const U_LAST: f64 = W_U_MIN + (W_N - 1) as f64 * W_U_STEP;

/// The parallel functions `(Y^A, Y^B, Y^C)`, `delta > 0`.
pub fn parallel(delta: f64) -> [f64; 3] {
    let u = libm::log10(delta);
    if u <= W_U_MIN {
        // Below the table: the logarithm's exact slope, its constant from the first node
        // (the remainder is O(delta ln delta), below 2e-4 here).
        let shift = libm::log(1.0 / delta) - W_U_MIN * -core::f64::consts::LN_10;
        return core::array::from_fn(|f| WALL[f][0] + NEAR_SLOPE[f] * shift);
    }
    if u >= U_LAST {
        // Beyond the table: the reflection series plus its error at the last node, which
        // falls off as (a/h)^6, so the two meet.
        let d_last = libm::pow(10.0, U_LAST);
        let (far, far_last) = (parallel_far(delta), parallel_far(d_last));
        let fade = libm::pow((1.0 + d_last) / (1.0 + delta), 6.0);
        return core::array::from_fn(|f| far[f] + (WALL[f][W_N - 1] - far_last[f]) * fade);
    }
    let (i0, w) = stencil((u - W_U_MIN) / W_U_STEP, W_N);
    core::array::from_fn(|f| (0..4).map(|b| w[b] * WALL[f][i0 + b]).sum())
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
