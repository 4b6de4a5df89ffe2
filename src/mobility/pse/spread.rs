//! Gaussian spreading onto the grid and interpolation back (the spectral Ewald method of
//! Lindbo & Tornberg, as PSE uses it).
//!
//! Each sphere carries two vector sources, packed as one complex value per component:
//! the force `F_j` (real part) and `a_j^2 F_j` (imaginary part). The wave-space kernel
//! then forms Beenakker's sphere factor `F_j - k^2 a_j^2 F_j / 6` exactly for every
//! radius (`wave.rs`), so polydispersity costs no extra transform: three complex FFTs
//! carry the six real fields. Interpolation reads the real part `U` and the imaginary
//! part `V = IFFT(k^2 u)` and forms `U - a_i^2 V / 6`, the same factor on the receiving
//! sphere.
//!
//! The Gaussian is `g(r) = (2 pi sigma^2)^{-3/2} exp(-r^2 / (2 sigma^2))`, truncated to
//! `P_d` points per axis around the sphere (every point left out is at least `P_d h_d
//! / 2` away).

use super::Pse;
use super::fft::Cx;
use crate::real::Real;

/// The largest support per axis, in grid points.
pub const MAX_SUPPORT: usize = 32;

/// One sphere's window: the grid index and Gaussian weight of each of its `P_d` points
/// per axis.
struct Window<T: Real> {
    index: [[usize; MAX_SUPPORT]; 3],
    weight: [[T; MAX_SUPPORT]; 3],
}

impl<T: Real> Window<T> {
    /// The window of a sphere at `pos` (any image: wrapped into the box first).
    #[inline(always)]
    fn new(pse: &Pse<T>, pos: T::V3) -> Self {
        let p = T::xyz(pse.cell.wrap_into(pos));
        let mut w = Self {
            index: [[0; MAX_SUPPORT]; 3],
            weight: [[T::ZERO; MAX_SUPPORT]; 3],
        };
        let half = T::ONE / (T::TWO * pse.sigma * pse.sigma);
        for d in 0..3 {
            let (m, h, support) = (pse.grid.m[d] as i64, pse.h[d], pse.support[d]);
            // First point: above p - P h / 2.
            let g0 = libm::floor((p[d] / h).to_f64() - 0.5 * support as f64) as i64 + 1;
            for t in 0..support {
                let g = g0 + t as i64;
                let x = T::from_f64(g as f64) * h - p[d];
                w.index[d][t] = g.rem_euclid(m) as usize;
                w.weight[d][t] = (-(x * x) * half).exp();
            }
        }
        for t in 0..pse.support[0] {
            w.weight[0][t] *= pse.norm;
        }
        w
    }
}

/// Calls `f(at, weight)` for each grid point of a window (`at` the first of its three
/// components), `z`, then `y`, then `x` ascending in the window: the fixed order of
/// both spreading and interpolation.
#[inline(always)]
fn visit<T: Real>(pse: &Pse<T>, w: &Window<T>, mut f: impl FnMut(usize, T)) {
    let [mx, my, _] = pse.grid.m;
    let [px, py, pz] = pse.support;
    for tz in 0..pz {
        let (iz, wz) = (w.index[2][tz], w.weight[2][tz]);
        for ty in 0..py {
            let wyz = w.weight[1][ty] * wz;
            let base = (w.index[1][ty] + my * iz) * mx;
            for tx in 0..px {
                f(3 * (base + w.index[0][tx]), w.weight[0][tx] * wyz);
            }
        }
    }
}

/// `grid` (3 components per point, zeroed by the caller) `+=` each sphere's Gaussian
/// times `(F_j, a_j^2 F_j)`, spheres in index order.
pub(super) fn spread<T: Real>(
    pse: &Pse<T>,
    pos: &[T::V3],
    radius: &[T],
    force: &[T::V3],
    grid: &mut [Cx<T>],
) {
    for j in 0..pos.len() {
        let w = Window::new(pse, pos[j]);
        let a2 = radius[j] * radius[j];
        let v = T::xyz(force[j]).map(|c| [c, a2 * c]);
        visit(pse, &w, |at, s| {
            for c in 0..3 {
                grid[at + c][0] += s * v[c][0];
                grid[at + c][1] += s * v[c][1];
            }
        });
    }
}

/// `out_i += sum_g g(x_g - r_i) (U(x_g) - a_i^2 V(x_g) / 6)` for every sphere, with
/// `U + i V` the grid after the inverse transform (the quadrature weight `h^3` is in the
/// wave-space kernel).
pub(super) fn interpolate<T: Real>(
    pse: &Pse<T>,
    pos: &[T::V3],
    radius: &[T],
    grid: &[Cx<T>],
    out: &mut [T::V3],
) {
    let sixth = T::ONE / T::from_f64(6.0);
    for i in 0..pos.len() {
        let w = Window::new(pse, pos[i]);
        let mut acc = [[T::ZERO; 2]; 3];
        visit(pse, &w, |at, s| {
            for c in 0..3 {
                acc[c][0] += s * grid[at + c][0];
                acc[c][1] += s * grid[at + c][1];
            }
        });
        let k = radius[i] * radius[i] * sixth;
        out[i] += T::v3(
            acc[0][0] - k * acc[0][1],
            acc[1][0] - k * acc[1][1],
            acc[2][0] - k * acc[2][1],
        );
    }
}
