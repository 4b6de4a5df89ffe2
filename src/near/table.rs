//! The tabulated remainders (function minus its singular part) between contact and the
//! far field, read with cubic Lagrange interpolation in `log10(lambda)` and in
//! `t = sqrt(xi / XI_MAX)` (the remainder's `xi^2 ln xi` leftover is smooth in `t`).

use super::lubrication::Func;
use super::tables::{N_L, N_T, REM, U_MIN, U_STEP, XI_MAX};

/// Node offset and the four cubic Lagrange weights for grid coordinate `g` on `n` nodes.
pub(super) fn stencil(g: f64, n: usize) -> (usize, [f64; 4]) {
    let i0 = (libm::floor(g) as i64 - 1).clamp(0, n as i64 - 4) as usize;
    let u = g - i0 as f64;
    let w = [
        -(u - 1.0) * (u - 2.0) * (u - 3.0) / 6.0,
        u * (u - 2.0) * (u - 3.0) / 2.0,
        -u * (u - 1.0) * (u - 3.0) / 2.0,
        u * (u - 1.0) * (u - 2.0) / 6.0,
    ];
    (i0, w)
}

/// Grid coordinates of `(l, xi)`: `log10(l)` and `t` in node units.
pub fn coords(l: f64, xi: f64) -> (f64, f64) {
    let u = (libm::log10(l) - U_MIN) / U_STEP;
    let t = libm::sqrt(xi / XI_MAX) * (N_T - 1) as f64;
    (u, t)
}

/// The remainder of `f` at size ratio `l` (within the table) and gap `0 <= xi <= XI_MAX`.
pub fn remainder(f: Func, l: f64, xi: f64) -> f64 {
    let (u, t) = coords(l, xi);
    let (i0, wu) = stencil(u, N_L);
    let (j0, wt) = stencil(t, N_T);
    let tab = &REM[f as usize];
    let mut sum = 0.0;
    for (a, wa) in wu.iter().enumerate() {
        let mut row = 0.0;
        for (b, wb) in wt.iter().enumerate() {
            row += wb * tab[(i0 + a) * N_T + j0 + b];
        }
        sum += wa * row;
    }
    sum
}
