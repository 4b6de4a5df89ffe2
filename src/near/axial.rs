//! Rotation about the line of centres (`X^C`): exact, in closed form.
//!
//! The swirl flow of two spheres turning about their common axis is a sum of image
//! rotlets at the points the two spheres' inversions map into each other (Jeffery 1915;
//! the bispherical form Jeffrey and Onishi 1984 quote). With bispherical coordinates
//! `sinh(alpha) = c / a1`, `sinh(beta) = c / a2`, `gamma = alpha + beta`:
//!
//! * `X^C_11 = sum_{n>=0} (sinh(alpha) / sinh(n gamma + alpha))^3`,
//! * `X^C_12 = -8 (c / (a1 + a2))^3 sum_{n>=1} csch(n gamma)^3`.
//!
//! Near contact the terms fall only as `n^-3`: the first [`TERMS`] are summed and the
//! rest is the midpoint rule's integral of `csch^3`, whose antiderivative is elementary
//! (relative error of the tail below `1e-6` of the tail itself).

/// Terms summed before the tail integral.
pub const TERMS: usize = 48;

/// `(q / sinh(y))^3`, as a ratio first: no overflow for far pairs' large `q` and `y`.
fn ratio3(q: f64, y: f64) -> f64 {
    let t = q / libm::sinh(y);
    t * t * t
}

/// `int_y^inf csch(t)^3 dt = (csch(y) coth(y) + ln(tanh(y / 2))) / 2`.
fn tail(y: f64) -> f64 {
    if y > 40.0 {
        // Both terms are below 1e-34: the tail is negligible (and coth overflows nothing).
        return 0.0;
    }
    let s = libm::sinh(y);
    0.5 * (libm::cosh(y) / (s * s) + libm::log(libm::tanh(0.5 * y)))
}

/// `sum_{n >= n0} (q / sinh(n gamma + shift))^3`.
pub(crate) fn csch3_sum(q: f64, gamma: f64, shift: f64, n0: usize) -> f64 {
    let mut sum = 0.0;
    for n in n0..n0 + TERMS {
        let term = ratio3(q, n as f64 * gamma + shift);
        sum += term;
        // Far apart the terms fall by exp(-3 gamma) each: once one is below the sum's
        // last bit, so is the rest (the sum of all later ones is below twice it).
        if gamma > 0.5 && !(term > 1e-17 * sum) {
            return sum;
        }
    }
    let t = tail((n0 + TERMS) as f64 * gamma - 0.5 * gamma + shift);
    if t == 0.0 {
        sum
    } else {
        sum + q * q * q * t / gamma
    }
}

/// `(X^C_11, X^C_12)` for radii `a1`, `a2` at centre distance `r > a1 + a2`.
pub fn xc(a1: f64, a2: f64, r: f64) -> (f64, f64) {
    // c^2 = z1^2 - a1^2 in factored form: no cancellation near contact, no overflow far.
    let (p, m) = ((a1 + a2) / r, (a1 - a2) / r);
    let c = 0.5 * r * libm::sqrt((1.0 - p) * (1.0 + p) * (1.0 - m) * (1.0 + m));
    let alpha = libm::asinh(c / a1);
    let beta = libm::asinh(c / a2);
    let gamma = alpha + beta;
    let x11 = csch3_sum(c / a1, gamma, alpha, 0);
    let x12 = -8.0 * csch3_sum(c / (a1 + a2), gamma, 0.0, 1);
    (x11, x12)
}
