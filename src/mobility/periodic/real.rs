//! The real-space half of the Ewald split: the free-space RPY block of every image
//! within the cutoff minus the smooth kernel `W` whose lattice sum the wave-space half
//! takes over (`docs/PERIODIC.md`, eqs. W and W0).

use super::{MAX_INDEX, Periodic, PeriodicError};
use crate::mobility::{Hydro, self_tt as free_self_tt};
use crate::real::Real;

/// What the real-space sum reads: the box, the splitting parameter, the cutoff and the
/// image range per axis. Shared by the Ewald path and the PSE near field
/// (`mobility::pse`), which sum the same real-space blocks.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Split<T: Real> {
    pub(crate) cell: Periodic<T>,
    pub(crate) xi: T,
    pub(crate) r_cut: T,
    /// Image index bound per axis: 0 where `r_cut < L_d / 2` (a minimum-image
    /// separation's other images are then at least `L_d / 2` away along that axis, so
    /// beyond the cutoff), else `ceil(r_cut / L_d + 1/2)`.
    images: [usize; 3],
}

impl<T: Real> Split<T> {
    /// The split for `xi` and `r_cut` (both positive, checked by the callers);
    /// [`PeriodicError::TooElongated`] past `MAX_INDEX` images on an axis.
    pub(crate) fn new(cell: Periodic<T>, xi: T, r_cut: f64) -> Result<Self, PeriodicError> {
        let mut images = [0; 3];
        for (d, l) in cell.size().into_iter().enumerate() {
            let l = l.to_f64();
            let m = if r_cut < 0.5 * l {
                0.0
            } else {
                libm::ceil(r_cut / l + 0.5)
            };
            if !(m <= MAX_INDEX as f64) {
                return Err(PeriodicError::TooElongated);
            }
            images[d] = m as usize;
        }
        Ok(Self {
            cell,
            xi,
            r_cut: T::from_f64(r_cut),
            images,
        })
    }
}

/// Terms of the power series of `W` below `xi r = 1` (the last one is below `1e-22`
/// relative there, for spheres up to the box's half width).
const SERIES_TERMS: usize = 28;

/// Coefficients `(A, B)` of `eta W(r) = A I + B e e^T`, the inverse transform of the
/// wave-space kernel `(I - k k / k^2) / k^2 (1 + k^2 / (4 xi^2)) exp(-k^2 / (4 xi^2))
/// (1 - k^2 a_i^2 / 6) (1 - k^2 a_j^2 / 6)` over all of `k`-space, at distance `s >= 0`.
/// `alpha = (a_i^2 + a_j^2) / 6`, `beta = a_i^2 a_j^2 / 36`.
///
/// `W` is entire in `s`; its closed form (erf and a Gaussian) cancels like `1/(xi s)^3`
/// near the origin, so below `xi s = 1` the power series in `(xi s)^2` is summed instead
/// (alternating, largest term `O(1)`: no cancellation to speak of).
#[inline(always)]
pub(super) fn smooth<T: Real>(xi: T, alpha: T, beta: T, s: T) -> (T, T) {
    let v = Scaled::new(xi, alpha, beta, s);
    if v.x < T::ONE { series(&v) } else { closed(&v) }
}

/// The arguments of [`smooth`] and the products both its forms read.
#[derive(Clone, Copy)]
struct Scaled<T: Real> {
    xi: T,
    alpha: T,
    s: T,
    /// `xi s` and its square.
    x: T,
    x2: T,
    /// `alpha xi^2`, `beta xi^4`: the sphere factors' dimensionless weights.
    axi2: T,
    bxi4: T,
}

impl<T: Real> Scaled<T> {
    #[inline(always)]
    fn new(xi: T, alpha: T, beta: T, s: T) -> Self {
        let (x, xi2) = (xi * s, xi * xi);
        Self {
            xi,
            alpha,
            s,
            x,
            x2: x * x,
            axi2: alpha * xi2,
            bxi4: beta * xi2 * xi2,
        }
    }
}

/// [`smooth`] by its power series in `(xi s)^2`.
#[inline(always)]
fn series<T: Real>(v: &Scaled<T>) -> (T, T) {
    let c = |v: f64| T::from_f64(v);
    let Scaled {
        xi, x2, axi2, bxi4, ..
    } = *v;
    {
        // A = k0 sum_n n u_{n-1} c_n, B = -k0 sum_n (n - 1) u_{n-1} c_n with
        // u_m = (-x^2)^m / m!, c_n = 1/(2n-1) - 2 alpha xi^2 (2n+3)/(2n+1) + 4 beta xi^4 (2n+5).
        let (mut a, mut b, mut u) = (T::ZERO, T::ZERO, T::ONE);
        for n in 1..=SERIES_TERMS {
            let nf = c(n as f64);
            let two_n = nf + nf;
            let cn = T::ONE / (two_n - T::ONE)
                - c(2.0) * axi2 * (two_n + c(3.0)) / (two_n + T::ONE)
                + c(4.0) * bxi4 * (two_n + c(5.0));
            a += nf * u * cn;
            b += (nf - T::ONE) * u * cn;
            u = -u * x2 / nf;
        }
        let k0 = xi / (T::TWO * T::PI * T::PI.sqrt());
        (k0 * a, -(k0 * b))
    }
}

/// [`smooth`] in closed form (accurate from `xi s` about 1 on).
#[inline(always)]
fn closed<T: Real>(v: &Scaled<T>) -> (T, T) {
    let (cg, erf) = gauss_erf(v.xi, v.x, v.x2);
    closed_from(v, cg, erf)
}

/// The closed forms' transcendental parts at `x = xi s`: `2 xi / sqrt(pi) exp(-x^2)`
/// and `erf(x)`, shared by [`smooth`]'s and the rotation blocks' closed forms.
#[inline(always)]
pub(super) fn gauss_erf<T: Real>(xi: T, x: T, x2: T) -> (T, T) {
    (T::from_f64(2.0) * xi / T::PI.sqrt() * (-x2).exp(), x.erf())
}

/// [`smooth`] from both closed forms' shared parts at once: `(A, B)` of [`smooth`] and
/// `(h'/r, A, B)` of the rotation blocks, the same bits as the two separately (one
/// exponential and one `erf` instead of two each).
#[inline(always)]
pub(super) fn smooth_with<T: Real>(
    xi: T,
    alpha: T,
    beta: T,
    s: T,
    rot: impl FnOnce(Option<(T, T)>) -> (T, T, T),
) -> ((T, T), (T, T, T)) {
    let v = Scaled::new(xi, alpha, beta, s);
    if v.x < T::ONE {
        (series(&v), rot(None))
    } else {
        let (cg, erf) = gauss_erf(v.xi, v.x, v.x2);
        (closed_from(&v, cg, erf), rot(Some((cg, erf))))
    }
}

/// [`closed`] with its transcendental parts given ([`gauss_erf`]).
#[inline(always)]
fn closed_from<T: Real>(v: &Scaled<T>, cg: T, erf: T) -> (T, T) {
    let c = |v: f64| T::from_f64(v);
    let Scaled {
        xi,
        alpha,
        s,
        x: _,
        x2,
        axi2,
        bxi4,
    } = *v;
    let xi2 = xi * xi;
    // Phi' = -p1 / (8 pi), Phi'' = -p2 / (8 pi) of the radial potential Phi with
    // eta W = grad grad Phi - I lap Phi; A = -(Phi'' + Phi'/s), B = Phi'' - Phi'/s.
    let inv = T::ONE / s;
    let inv2 = inv * inv;
    let t2p = -(c(2.0) * axi2 * s * cg);
    let t2pp = -(c(2.0) * axi2 * (T::ONE - c(2.0) * x2) * cg);
    let t3p = c(2.0) * alpha * (cg * inv - erf * inv2);
    let t3pp =
        c(2.0) * alpha * (c(2.0) * erf * inv2 * inv - c(2.0) * cg * inv2 - c(2.0) * xi2 * cg);
    let t4p = bxi4 * s * cg * (c(28.0) - c(8.0) * x2);
    let t4pp = bxi4 * cg * (c(28.0) - c(80.0) * x2 + c(16.0) * x2 * x2);
    let p1 = erf + t2p + t3p + t4p;
    let p2 = cg + t2pp + t3pp + t4pp;
    let k = T::ONE / (c(8.0) * T::PI);
    (k * (p2 + p1 * inv), k * (p1 * inv - p2))
}

/// The real-space sum for the pair `(i, j)` at minimum-image separation `r0` (for
/// `same`, the self block: `r0` is zero and the image `n = 0` is the sphere itself,
/// `1/(6 pi eta a) - W(0)`). Images in a fixed order (`n_x`, then `n_y`, then `n_z`,
/// each ascending), every one with `|r0 + n L| <= r_cut`. `None` when an image of one
/// sphere lies inside the other (as [`crate::mobility::pair_tt`]).
pub(crate) fn real_sum<T: Real>(
    ew: &Split<T>,
    eta: T,
    ai: T,
    aj: T,
    r0: T::V3,
    same: bool,
) -> Option<T::M3> {
    let six = T::from_f64(6.0);
    let alpha = (ai * ai + aj * aj) / six;
    let beta = ai * ai * aj * aj / (six * six);
    let inv_eta = T::ONE / eta;
    let mut acc = T::M3_ZERO;
    for_each_image(ew, r0, |origin, rn, s2| {
        if same && origin {
            let (a0, _) = smooth(ew.xi, alpha, beta, T::ZERO);
            acc += T::m3_diag(free_self_tt(eta, ai) - a0 * inv_eta);
            return Some(());
        }
        let rpy = crate::mobility::pair_tt(Hydro::Rpy, eta, ai, aj, rn)?;
        let (s, inv_s) = s2.root_and_inverse();
        let e = rn * inv_s;
        let (a, b) = smooth(ew.xi, alpha, beta, s);
        let w = T::m3_add_diag(T::outer(e, e) * (b * inv_eta), a * inv_eta);
        acc += rpy - w;
        Some(())
    })?;
    Some(acc)
}

/// Calls `f(origin, r0 + n L, |r0 + n L|^2)` for every image `n` with
/// `|r0 + n L| <= r_cut`, in a fixed order (`n_x`, then `n_y`, then `n_z`, each
/// ascending; `origin` for `n = 0`); stops at the first `None` and returns it.
#[inline(always)]
pub(super) fn for_each_image<T: Real>(
    ew: &Split<T>,
    r0: T::V3,
    mut f: impl FnMut(bool, T::V3, T) -> Option<()>,
) -> Option<()> {
    let [lx, ly, lz] = ew.cell.size();
    let [mx, my, mz] = ew.images.map(|m| m as i32);
    let rc2 = ew.r_cut * ew.r_cut;
    for nx in -mx..=mx {
        for ny in -my..=my {
            for nz in -mz..=mz {
                let shift = T::v3(
                    T::from_f64(nx as f64) * lx,
                    T::from_f64(ny as f64) * ly,
                    T::from_f64(nz as f64) * lz,
                );
                let rn = r0 + shift;
                let s2 = T::norm2(rn);
                if !(s2 <= rc2) {
                    continue;
                }
                f(nx == 0 && ny == 0 && nz == 0, rn, s2)?;
            }
        }
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::{Scaled, closed, series, smooth};

    /// The series and the closed form agree around the switch at `xi r = 1`, and far
    /// out `W` is the far-field RPY block `(1 + q/3) I + (1 - q) e e` over `8 pi r`,
    /// `q = (a_i^2 + a_j^2) / r^2`.
    #[test]
    fn series_meets_closed_form_and_far_field() {
        for (ai, aj, xi) in [
            (1.0f64, 1.0, 0.3),
            (1.0, 0.3, 1.0),
            (2.0, 0.5, 0.5),
            (0.4, 0.4, 2.4),
        ] {
            let (alpha, beta) = ((ai * ai + aj * aj) / 6.0, ai * ai * aj * aj / 36.0);
            for x in [0.8, 1.0, 1.3] {
                let v = Scaled::new(xi, alpha, beta, x / xi);
                let (s, c) = (series(&v), closed(&v));
                let scale = s.0.abs().max(s.1.abs());
                let d = (s.0 - c.0).abs().max((s.1 - c.1).abs()) / scale;
                assert!(d < 5e-15, "a {ai} {aj} xi {xi} x {x}: {d:e}");
            }
            let r = 9.0 / xi;
            let (a, b) = smooth(xi, alpha, beta, r);
            let (q, c) = (
                (ai * ai + aj * aj) / (r * r),
                1.0 / (8.0 * core::f64::consts::PI * r),
            );
            assert!(
                (a - c * (1.0 + q / 3.0)).abs() < 1e-15 * c
                    && (b - c * (1.0 - q)).abs() < 1e-15 * c
            );
        }
    }
}
