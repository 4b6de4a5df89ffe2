//! The far part's radial functions: the Stokeslet smoothed by a Gaussian of variance
//! `s^2`, with the sphere factors `(1 + a_i^2 lap / 6)(1 + a_j^2 lap / 6)`.
//!
//! Every tensor here is `(I lap - grad grad) F(r)` for a radial `F`. Written with
//! `u = r^2`, `F'(r) / r = 2 F_u` and `F'' - F' / r = 4 u F_uu`, so
//! `(I lap - grad grad) F = (4 F_u + 4 u F_uu) I - 4 F_uu r r^T`: only `F_u` and `F_uu`
//! are needed, both smooth at `u = 0`. With `b = 1 / (sqrt(2) s)`, `x = b r`:
//!
//! * `Phi` (with `lap Phi = psi`): the biharmonic `r / (8 pi)` smoothed,
//!   `Phi_u = b / (32 pi) ((2x^2 - 1) erf x + 2/sqrt(pi) x e^{-x^2}) / x^3`;
//! * `psi = erf(x) / (4 pi r)` (with `lap psi = -g`), the smoothed `1 / (4 pi r)`;
//! * `g = (b^2 / pi)^{3/2} e^{-x^2}`, the Gaussian itself.
//!
//! `F = Phi + (alpha_i + alpha_j) psi - alpha_i alpha_j g` with `alpha = a^2 / 6`. The
//! closed forms lose digits to cancellation at small `x`; below `x = 1` the functions
//! are summed from their power series in `y = x^2` instead, whose coefficients follow
//! from `Phi_u`'s by `lap` (`(lap f)_u` from `f_u`'s series term by term).

use core::f64::consts::PI;

/// Series terms (the last one below `1e-18` of the first at `y = 1`).
const TERMS: usize = 24;

/// `x^2` below which the series is summed.
const SERIES_BELOW: f64 = 1.0;

/// The radial functions for one `b` and `beta`, with the series' coefficients and the
/// Gaussian's normalisation computed once (they cost more than a pair's evaluation).
pub(super) struct Radial {
    b: f64,
    beta: f64,
    /// `(b^2 / pi)^{3/2}`.
    g0: f64,
    /// `Phi_u`'s series coefficients `d_m` and `psi_u`'s `q_m`.
    d: [f64; TERMS + 2],
    q: [f64; TERMS + 1],
}

impl Radial {
    pub(super) fn new(b: f64, beta: f64) -> Self {
        let mut d = [0.0; TERMS + 2];
        let mut fact = 1.0;
        for (m, dm) in d.iter_mut().enumerate() {
            let n = (m + 1) as f64;
            fact *= n;
            let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
            *dm = sign * 4.0 * n / (fact * (4.0 * n * n - 1.0));
        }
        let mut q = [0.0; TERMS + 1];
        for (m, qm) in q.iter_mut().enumerate() {
            *qm = (m as f64 + 1.0) * (10.0 + 4.0 * m as f64) * d[m + 1];
        }
        Self {
            b,
            beta,
            g0: libm::pow(b * b / PI, 1.5),
            d,
            q,
        }
    }

    /// `[Phi_u, psi_u, g_u, zeta_u]` and `[Phi_uu, psi_uu, g_uu, zeta_uu]` at `u = r^2`,
    /// with `zeta = lap g`.
    pub(super) fn derivatives(&self, u: f64) -> ([f64; 4], [f64; 4]) {
        let b2 = self.b * self.b;
        let y = b2 * u;
        // The Gaussian and its Laplacian `g0 b^2 e^{-y} (4 y - 6)` have no cancellation.
        let gauss = libm::exp(-y);
        let g = self.g0 * gauss;
        let (g_u, g_uu) = (-b2 * g, b2 * b2 * g);
        let zeta_u = b2 * b2 * g * (10.0 - 4.0 * y);
        let zeta_uu = b2 * b2 * b2 * g * (4.0 * y - 14.0);
        let (phi, psi) = if y < SERIES_BELOW {
            self.series(y)
        } else {
            closed(self.b, u, g, gauss)
        };
        ([phi.0, psi.0, g_u, zeta_u], [phi.1, psi.1, g_uu, zeta_uu])
    }

    /// `(Phi_u, Phi_uu)` and `(psi_u, psi_uu)` from the series in `y = b^2 u`: `Phi_u = k
    /// sum d_m y^m`, `psi_u = k b^2 sum q_m y^m`, where a term `c_m y^m` of `f_u` gives
    /// `(lap f)_u`'s term `(m + 1)(10 + 4 m) c_{m+1} b^2 y^m`.
    fn series(&self, y: f64) -> ((f64, f64), (f64, f64)) {
        let b = self.b;
        let b2 = b * b;
        let k = b / (16.0 * libm::pow(PI, 1.5));
        // f_u = sum c_m y^m; f_uu = b^2 sum (m + 1) c_{m+1} y^m (Horner, fixed order).
        let sum = |c: &[f64]| c[..TERMS].iter().rev().fold(0.0, |acc, &cm| acc * y + cm);
        let dsum = |c: &[f64]| {
            (0..TERMS)
                .rev()
                .fold(0.0, |acc, m| acc * y + (m as f64 + 1.0) * c[m + 1])
        };
        let (k2, k4) = (k * b2, k * b2 * b2);
        let (d, q) = (&self.d, &self.q);
        ((k * sum(d), k2 * dsum(d)), (k2 * sum(q), k4 * dsum(q)))
    }

    /// The far block's scalars `(c_I, c_rr)` (block `= (c_I I + c_rr r r^T) / eta`) at
    /// `u = r^2`: `F = (1 - beta lap)(1 + alpha_i lap)(1 + alpha_j lap) Phi`, sphere
    /// factors `alpha = a^2 / 6`. `beta = s^2 / 2` (Hasimoto's factor `1 + k^2 s^2 / 2`)
    /// makes the far field the plain Stokeslet beyond the Gaussian: a Gaussian of
    /// variance `s^2` alone would leave `(s^2 / 2) lap G`, a `1 / r^3` field.
    pub(super) fn far(&self, alpha: (f64, f64), u: f64) -> (f64, f64) {
        self.far_from(alpha, u, self.derivatives(u))
    }

    /// [`Radial::far`] from [`Radial::derivatives`] at `u`.
    fn far_from(&self, alpha: (f64, f64), u: f64, (d1, d2): ([f64; 4], [f64; 4])) -> (f64, f64) {
        let (s, p) = (alpha.0 + alpha.1, alpha.0 * alpha.1);
        let beta = self.beta;
        // lap Phi = psi, lap psi = -g, lap g = zeta.
        let c = [1.0, s - beta, -(p - beta * s), beta * p];
        let f_u: f64 = (0..4).map(|k| c[k] * d1[k]).sum();
        let f_uu: f64 = (0..4).map(|k| c[k] * d2[k]).sum();
        (4.0 * f_u + 4.0 * u * f_uu, -4.0 * f_uu)
    }

    /// The far part's rotation scalars at `u = r^2`, with `r = x_i - x_j`: `[h_i, h_j,
    /// c_I, c_rr]`, the rotation of `i` from a force on `j` being `h_j r x F` (and the
    /// translation of `i` from a torque on `j`, `h_i r x T`), and from a torque
    /// `(c_I I + c_rr r r^T) T` (all over `eta`).
    ///
    /// A torque is the force density `curl(T g) / 2` and a rotation half the curl of
    /// the velocity, so with `G = (I lap - grad grad) F`: `curl (G F) / 2 = (lap F)_u r x
    /// F` for `F = (1 - beta lap)(1 + alpha lap) Phi` (the sphere factor on the
    /// translating side alone), and `curl curl (G T) / 4 = (grad grad f - I lap f) T / 4`
    /// for `f = lap F = psi + beta g` (no sphere factor): `c_I = -f_u - u f_uu`, `c_rr =
    /// f_uu`. Far away `h = -1 / (8 pi r^3)` and `(3 e e - I) / (16 pi r^3)`: RPY's
    /// rotlet and rotation blocks.
    pub(super) fn rotation(&self, alpha: (f64, f64), u: f64) -> [f64; 4] {
        self.rotation_from(alpha, u, self.derivatives(u))
    }

    /// [`Radial::far`] and [`Radial::rotation`] from one evaluation of the functions.
    pub(super) fn grand(&self, alpha: (f64, f64), u: f64) -> ((f64, f64), [f64; 4]) {
        let d = self.derivatives(u);
        (self.far_from(alpha, u, d), self.rotation_from(alpha, u, d))
    }

    fn rotation_from(&self, alpha: (f64, f64), u: f64, (d1, d2): ([f64; 4], [f64; 4])) -> [f64; 4] {
        let beta = self.beta;
        // lap F = psi - (alpha - beta) g + beta alpha zeta.
        let h = |a: f64| d1[1] - (a - beta) * d1[2] + beta * a * d1[3];
        let (f_u, f_uu) = (d1[1] + beta * d1[2], d2[1] + beta * d2[2]);
        [h(alpha.0), h(alpha.1), -f_u - u * f_uu, f_uu]
    }
}

/// The closed forms of [`Radial::series`] (`x = b r >= 1`), `g` the Gaussian at `u` and
/// `gauss = e^{-b^2 u}`.
fn closed(b: f64, u: f64, g: f64, gauss: f64) -> ((f64, f64), (f64, f64)) {
    let b2 = b * b;
    let y = b2 * u;
    let x = libm::sqrt(y);
    let r = x / b;
    let erf = libm::erf(x);
    let two_rtpi = 2.0 / libm::sqrt(PI);
    let x3 = x * y;
    let phi_u = b / (32.0 * PI) * ((2.0 * y - 1.0) * erf + two_rtpi * x * gauss) / x3;
    let psi_u = b * b2 / (8.0 * PI * x3) * (two_rtpi * x * gauss - erf);
    let psi = erf / (4.0 * PI * r);
    // lap f = 6 f_u + 4 u f_uu.
    let phi_uu = (psi - 6.0 * phi_u) / (4.0 * u);
    let psi_uu = (-g - 6.0 * psi_u) / (4.0 * u);
    ((phi_u, phi_uu), (psi_u, psi_uu))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The series and the closed forms agree where they meet (`x = 1`), and far away
    /// the block is the Rotne-Prager far field `(1 + (a_i^2 + a_j^2) lap / 6)` of the
    /// Stokeslet, `((1 + A / (3 r^2)) I + (1 - A / r^2) e e) / (8 pi r)`, `A = a_i^2 + a_j^2`.
    #[test]
    fn series_meets_closed_form_and_far_field_is_rpy() {
        let b = 0.7;
        let u = 1.0 / (b * b);
        let beta = 1.0 / (4.0 * b * b);
        let rad = Radial::new(b, beta);
        let (s1, s2) = rad.derivatives(u * (1.0 - 1e-12));
        let (c1, c2) = rad.derivatives(u * (1.0 + 1e-12));
        for k in 0..4 {
            assert!(
                (s1[k] - c1[k]).abs() <= 1e-9 * c1[k].abs(),
                "{k}: {s1:?} {c1:?}"
            );
            assert!(
                (s2[k] - c2[k]).abs() <= 1e-9 * c2[k].abs(),
                "{k}: {s2:?} {c2:?}"
            );
        }
        let (ai, aj) = (1.0, 0.6);
        let r = 40.0;
        let (ci, crr) = rad.far((ai * ai / 6.0, aj * aj / 6.0), r * r);
        let a2 = ai * ai + aj * aj;
        let want_i = (1.0 + a2 / (3.0 * r * r)) / (8.0 * PI * r);
        let want_rr = (1.0 - a2 / (r * r)) / (8.0 * PI * r * r * r);
        assert!((ci - want_i).abs() <= 1e-13 * want_i, "{ci} {want_i}");
        assert!((crr - want_rr).abs() <= 1e-13 * want_rr, "{crr} {want_rr}");
        // The rotlet `-1 / (8 pi r^3)` (of `r x F`) and `(3 e e - I) / (16 pi r^3)`.
        let [hi, hj, ri, rrr] = rad.rotation((ai * ai / 6.0, aj * aj / 6.0), r * r);
        let rot = -1.0 / (8.0 * PI * r * r * r);
        let rr_i = -1.0 / (16.0 * PI * r * r * r);
        let rr_rr = 3.0 / (16.0 * PI * r * r * r * r * r);
        for (got, want) in [(hi, rot), (hj, rot), (ri, rr_i), (rrr, rr_rr)] {
            assert!((got - want).abs() <= 1e-13 * want.abs(), "{got} {want}");
        }
    }
}
