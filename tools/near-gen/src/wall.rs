//! Exact resistance of a sphere moving parallel to a plane wall, from the bispherical
//! coordinate solutions of O'Neill (1964, translation parallel to the wall) and Dean and
//! O'Neill (1963, rotation about an axis parallel to the wall), the solutions Goldman,
//! Cox and Brenner (1967) tabulated.
//!
//! With `cosh(alpha) = h / a`, both reduce to one three-term recurrence for coefficients
//! `A_n` (`n >= 1`, `A_0 = 0`),
//! `(n-1)/(2n-1) c_n A_{n-1} - (n c_n + (n+1) d_n)/(2n+1) A_n + (n+2)/(2n+3) d_n A_{n+1} = r_n`
//! with `k_n = (n+1/2) coth((n+1/2) alpha) - coth(alpha)`, `c_n = (2n-1) k_{n-1} - (2n-3) k_n`
//! and `d_n = (2n+5) k_n - (2n+3) k_{n+1}`; only the right-hand side `r_n` and two
//! particular terms differ between the motions. The force and torque are sums over the
//! `A_n` (below). The system is truncated where `(n + 1/2) alpha` passes `TAIL`, so the
//! neglected coefficients are below `e^-TAIL` of the first ones.

/// How far in `(n + 1/2) alpha` the expansion is carried.
pub const TAIL: f64 = 60.0;

/// The motion whose resistance is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// Translation parallel to the wall, no rotation (O'Neill 1964).
    Translation,
    /// Rotation about an axis parallel to the wall, no translation (Dean and O'Neill 1963).
    Rotation,
}

/// Force and torque on a sphere in `motion` at gap `delta = h/a - 1`, normalised as the
/// kernel's functions: the force by `6 pi eta a U` (translation) or `6 pi eta a^2 W`
/// (rotation), the torque by `8 pi eta a^2 U` or `8 pi eta a^3 W`; both positive (they
/// oppose the motion, and translation turns the sphere in the rolling sense). `terms`
/// coefficients are kept.
pub fn force_torque(delta: f64, motion: Motion, terms: usize) -> (f64, f64) {
    let alpha = (1.0 + delta).acosh();
    let (sh, cth) = (alpha.sinh(), 1.0 / alpha.tanh());
    let half = |n: usize| (n as f64 + 0.5) * alpha;
    let k: Vec<f64> = (0..terms + 2)
        .map(|n| (n as f64 + 0.5) / half(n).tanh() - cth)
        .collect();
    // L_n, the rotation's extra particular term.
    let l = |n: usize| {
        let nf = n as f64;
        -((-(nf - 0.5) * alpha).exp() / (2.0 * nf - 1.0)
            - (-(nf + 1.5) * alpha).exp() / (2.0 * nf + 3.0))
            / 2f64.sqrt()
    };
    // The tridiagonal system, rows n = 1..=terms (index n - 1), solved by elimination.
    let mut diag = Vec::with_capacity(terms);
    let mut upper = Vec::with_capacity(terms);
    let mut rhs = Vec::with_capacity(terms);
    let mut lower = Vec::with_capacity(terms);
    for n in 1..=terms {
        let nf = n as f64;
        let c = (2.0 * nf - 1.0) * k[n - 1] - (2.0 * nf - 3.0) * k[n];
        let d = (2.0 * nf + 5.0) * k[n] - (2.0 * nf + 3.0) * k[n + 1];
        lower.push((nf - 1.0) / (2.0 * nf - 1.0) * c);
        diag.push(-(nf * c + (nf + 1.0) * d) / (2.0 * nf + 1.0));
        upper.push((nf + 2.0) / (2.0 * nf + 3.0) * d);
        let csch = |x: f64| 1.0 / x.sinh();
        rhs.push(match motion {
            Motion::Translation => {
                2f64.sqrt()
                    * (2.0 / half(n).tanh() - 1.0 / half(n - 1).tanh() - 1.0 / half(n + 1).tanh())
            }
            Motion::Rotation => {
                let b = (2.0 * nf + 1.0).powi(2)
                    * (alpha.exp() / (2.0 * nf - 1.0) + (-alpha).exp() / (2.0 * nf + 3.0))
                    * csch(half(n))
                    - (2.0 * nf - 1.0) * csch(half(n - 1))
                    - (2.0 * nf + 3.0) * csch(half(n + 1));
                -2f64.sqrt() * (-half(n)).exp() / ((2.0 * nf + 1.0) * sh) * b
            }
        });
    }
    for i in 1..terms {
        let m = lower[i] / diag[i - 1];
        diag[i] -= m * upper[i - 1];
        rhs[i] -= m * rhs[i - 1];
    }
    let mut a = vec![0.0; terms + 2]; // a[n] = A_n; A_0 and A_{terms+1} are zero
    for n in (1..=terms).rev() {
        a[n] = (rhs[n - 1] - upper[n - 1] * a[n + 1]) / diag[n - 1];
    }
    let (mut fsum, mut tsum) = (0.0, 0.0);
    for n in 0..terms {
        let nf = n as f64;
        let prev = if n >= 1 { a[n - 1] } else { 0.0 };
        let s = half(n).sinh();
        let mut e = k[n]
            * ((nf - 1.0) * nf / (2.0 * nf - 1.0) * prev
                - (nf + 1.0) * (nf + 2.0) / (2.0 * nf + 3.0) * a[n + 1]);
        e += match motion {
            Motion::Translation => 2.0 * 2f64.sqrt() * (-half(n)).exp() / s,
            Motion::Rotation => (2f64.sqrt() * (2.0 * nf + 1.0) * (-half(n)).exp() - l(n) / sh) / s,
        };
        let (mut c, mut b) = (0.0, 0.0);
        if n >= 1 {
            c = -2.0
                * k[n]
                * ((nf - 1.0) / (2.0 * nf - 1.0) * prev - a[n]
                    + (nf + 2.0) / (2.0 * nf + 3.0) * a[n + 1]);
            if motion == Motion::Rotation {
                c += 4.0 * l(n) / (sh * s);
            }
            b = (nf - 1.0) * prev - (2.0 * nf + 1.0) * a[n] + (nf + 2.0) * a[n + 1];
        }
        let dn = 0.5 * ((nf + 1.0) * (nf + 2.0) * a[n + 1] - (nf - 1.0) * nf * prev);
        fsum += e + nf * (nf + 1.0) * c;
        let ea = (-(2.0 * nf + 1.0) * alpha).exp();
        let nn = nf * (nf + 1.0);
        tsum += (2.0 + ea) * (nn * (2.0 * a[n] + c * cth) - (2.0 * nf + 1.0 - cth) * e)
            + (2.0 - ea) * (nn * b * cth - (2.0 * nf + 1.0 - cth) * dn);
    }
    let r2 = 2f64.sqrt();
    match motion {
        Motion::Translation => (r2 / 6.0 * sh * fsum, tsum * sh * sh / (12.0 * r2)),
        Motion::Rotation => (
            -r2 / 6.0 * sh * sh * fsum,
            (1.0 - tsum * sh * sh * sh / (4.0 * r2)) / 3.0,
        ),
    }
}

/// Coefficients kept at gap `delta`: up to `(n + 1/2) alpha = TAIL`, at least 20.
pub fn terms_for(delta: f64) -> usize {
    let alpha = (1.0 + delta).acosh();
    (TAIL / alpha).ceil() as usize + 20
}

/// The kernel's `(Y^A_w, Y^B_w, Y^C_w)` at gap `delta`, `Y^B_w` from the translation's
/// torque (the rotation's force gives the same, by the reciprocal theorem).
pub fn parallel_exact(delta: f64) -> [f64; 3] {
    let n = terms_for(delta);
    let (ya, yb) = force_torque(delta, Motion::Translation, n);
    let (_, yc) = force_torque(delta, Motion::Rotation, n);
    [ya, yb, yc]
}
