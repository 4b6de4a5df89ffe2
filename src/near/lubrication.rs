//! Lubrication (near-contact) forms of the two-sphere resistance functions: the
//! `g`-functions of the size ratio `lambda = a2 / a1` (Jeffrey and Onishi 1984; the
//! unequal-sphere set as Townsend 2018 rederives it) and the singular basis functions
//! whose `1/s` series are known in closed form.
//!
//! Each function near contact is `g1 / xi + g2 ln(1/xi) + g3 xi ln(1/xi) + O(1)`, with
//! `xi = s - 2` and `s = 2 r / (a1 + a2)`. The kernel writes the singular part with
//! basis functions that have exactly these singularities and an elementary series in
//! `x = 2 / s` ([`basis`]); what is left (the remainder) is smooth and tabulated.

/// One of the eight resistance functions that come from the twin-multipole series
/// (`X^C` has an exact closed form, [`super::axial`]). The order is the tables' order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Func {
    /// `X^A_11`: force along the line of centres from sphere 1's own motion.
    X11A,
    /// `X^A_12`.
    X12A,
    /// `Y^A_11`: transverse force from transverse motion.
    Y11A,
    /// `Y^A_12`.
    Y12A,
    /// `Y^B_11`: torque from transverse motion.
    Y11B,
    /// `Y^B_12`.
    Y12B,
    /// `Y^C_11`: transverse torque from transverse rotation.
    Y11C,
    /// `Y^C_12`.
    Y12C,
}

fn c3(l: f64) -> f64 {
    (1.0 + l) * (1.0 + l) * (1.0 + l)
}

impl Func {
    /// All eight, in table order.
    pub const ALL: [Func; 8] = [
        Func::X11A,
        Func::X12A,
        Func::Y11A,
        Func::Y12A,
        Func::Y11B,
        Func::Y12B,
        Func::Y11C,
        Func::Y12C,
    ];

    /// The series in `x = 2 / s` has odd powers only (else even).
    pub fn odd(self) -> bool {
        matches!(self, Func::X12A | Func::Y12A | Func::Y11B | Func::Y12C)
    }

    /// Jeffrey and Onishi's factor in front of the series (1 for the `11` functions).
    pub fn prefactor(self, l: f64) -> f64 {
        match self {
            Func::X12A | Func::Y12A => -2.0 / (1.0 + l),
            Func::Y12B => -4.0 / ((1.0 + l) * (1.0 + l)),
            Func::Y12C => 8.0 / c3(l),
            _ => 1.0,
        }
    }

    /// Coefficients of `1/xi`, `ln(1/xi)` and `xi ln(1/xi)` near contact.
    pub fn singular(self, l: f64) -> [f64; 3] {
        let l2 = l * l;
        let (l3, l4) = (l2 * l, l2 * l2);
        let g = match self {
            Func::X11A | Func::X12A => [
                2.0 * l2 / c3(l),
                l * (1.0 + 7.0 * l + l2) / (5.0 * c3(l)),
                (1.0 + 18.0 * l - 29.0 * l2 + 18.0 * l3 + l4) / (42.0 * c3(l)),
            ],
            Func::Y11A | Func::Y12A => [
                0.0,
                4.0 * l * (2.0 + l + 2.0 * l2) / (15.0 * c3(l)),
                2.0 * (16.0 - 45.0 * l + 58.0 * l2 - 45.0 * l3 + 16.0 * l4) / (375.0 * c3(l)),
            ],
            Func::Y11B | Func::Y12B => {
                let d = (1.0 + l) * (1.0 + l);
                [
                    0.0,
                    -l * (4.0 + l) / (5.0 * d),
                    -(32.0 - 33.0 * l + 83.0 * l2 + 43.0 * l3) / (250.0 * d),
                ]
            }
            Func::Y11C => [
                0.0,
                2.0 * l / (5.0 * (1.0 + l)),
                (8.0 + 6.0 * l + 33.0 * l2) / (125.0 * (1.0 + l)),
            ],
            Func::Y12C => [
                0.0,
                l2 / (10.0 * (1.0 + l)),
                l * (43.0 - 24.0 * l + 43.0 * l2) / (500.0 * (1.0 + l)),
            ],
        };
        let p = match self {
            Func::X11A | Func::Y11A | Func::Y11B | Func::Y11C => 1.0,
            _ => self.prefactor(l),
        };
        [g[0] * p, g[1] * p, g[2] * p]
    }
}

/// The singular basis functions at `xi = s - 2 > 0`, with `x = 2 / s`:
/// even `1/(1-x^2)`, `-ln(1-x^2)`, `-(1-x^2) ln(1-x^2)`; odd `x/(1-x^2)`,
/// `ln((1+x)/(1-x))`, `(1-x^2) ln((1+x)/(1-x))`. Near contact they behave as `1/xi`,
/// `ln(1/xi)` and `xi ln(1/xi)` plus smooth terms. `1 - x^2` is formed as
/// `xi (xi + 4) / (xi + 2)^2`, so nothing cancels as `xi` goes to zero.
pub fn basis(odd: bool, xi: f64) -> [f64; 3] {
    let x = 2.0 / (2.0 + xi);
    let w = xi * (xi + 4.0) / ((xi + 2.0) * (xi + 2.0));
    if odd {
        let lg = libm::log((2.0 + xi) * (1.0 + x) / xi);
        [x / w, lg, w * lg]
    } else {
        let lg = -libm::log(w);
        [1.0 / w, lg, w * lg]
    }
}

/// The singular part of `f` at size ratio `l` and gap `xi`.
pub fn singular_part(f: Func, l: f64, xi: f64) -> f64 {
    let g = f.singular(l);
    let b = basis(f.odd(), xi);
    g[0] * b[0] + g[1] * b[1] + g[2] * b[2]
}

/// Coefficient of `x^k` in the series of singular basis function `i` (0, 1, 2).
pub fn basis_coeff(odd: bool, i: usize, k: usize) -> f64 {
    if (k % 2 == 1) != odd {
        return 0.0;
    }
    let kf = k as f64;
    match (odd, i, k) {
        (_, 0, _) => 1.0,
        (false, _, 0) => 0.0,
        (_, 1, _) => 2.0 / kf,
        (false, 2, 2) | (true, 2, 1) => {
            if odd {
                2.0
            } else {
                1.0
            }
        }
        (_, 2, _) => -4.0 / (kf * (kf - 2.0)),
        _ => 0.0,
    }
}
