//! The far part on the grid: spreading with the sphere factor onto the cloud's grid,
//! the aperiodic convolution ([`spectral`]), and interpolation.
//!
//! The cloud's grid has `m` points per axis from the bounding box's lower corner, less
//! the window's reach. The kernel is sampled at the offsets `-(m - 1) ..= m - 1` per
//! axis (smooth, so sampling it is spectrally accurate).

use super::{FreeFast, radial, spectral};
use crate::mobility::pse::fft::Cx;
use crate::real::Real;

/// The kernel's transform into its octant of `reals`, with the quadrature weight `h^3`
/// and the inverse transform's `1 / P^3` folded in (viscosity 1).
pub(super) fn kernel<T: Real>(ff: &FreeFast<T>, cx: &mut [Cx<T>], reals: &mut [T]) {
    let plan = &ff.plan;
    let [mx, my, mz] = plan.m;
    let points = plan.p.iter().product::<usize>();
    let rad = radial::Radial::new(1.0 / (2.0 * ff.sigma), 2.0 * ff.sigma * ff.sigma);
    let (octant, table) = plan.split_reals(reals);
    for z in 0..mz {
        for y in 0..my {
            for x in 0..mx {
                let d = [x, y, z].map(|i| i as f64 * ff.h);
                let u = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                // Hasimoto's factor of the whole split (variance `4 sigma^2`), not the
                // residual's.
                let (ci, crr) = rad.far((0.0, 0.0), u);
                let t = 2 * (x + mx * (y + my * z));
                table[t] = T::from_f64(ci);
                table[t + 1] = T::from_f64(crr);
            }
        }
    }
    let weight = ff.h * ff.h * ff.h / points as f64;
    spectral::kernel(plan, cx, octant, table, (ff.h, weight));
}

/// One sphere's window: first grid index per axis, the Gaussian factor and the squared
/// distance of each point per axis.
struct Window {
    first: [usize; 3],
    gauss: [[f64; super::MAX_SUPPORT]; 3],
    dist2: [[f64; super::MAX_SUPPORT]; 3],
}

impl Window {
    fn new<T: Real>(ff: &FreeFast<T>, origin: [f64; 3], p: [f64; 3]) -> Self {
        let mut w = Self {
            first: [0; 3],
            gauss: [[0.0; super::MAX_SUPPORT]; 3],
            dist2: [[0.0; super::MAX_SUPPORT]; 3],
        };
        let half = 1.0 / (2.0 * ff.sigma * ff.sigma);
        for d in 0..3 {
            let g0 = libm::ceil((p[d] - origin[d] - ff.reach) / ff.h).max(0.0) as usize;
            w.first[d] = g0;
            for t in 0..ff.support {
                let x = origin[d] + (g0 + t) as f64 * ff.h - p[d];
                w.dist2[d][t] = x * x;
                w.gauss[d][t] = libm::exp(-x * x * half);
            }
        }
        w
    }

    /// Calls `f(point, weight)` over the window, `weight` the Gaussian with the sphere
    /// factor `(1 + alpha lap)` and the normalisation `norm`.
    fn visit(
        &self,
        (sigma, n): (f64, usize),
        alpha: f64,
        px: [usize; 2],
        mut f: impl FnMut(usize, f64),
    ) {
        let s2 = sigma * sigma;
        let norm = libm::pow(2.0 * core::f64::consts::PI * s2, -1.5);
        let (a0, a1) = (1.0 - 3.0 * alpha / s2, alpha / (s2 * s2));
        for tz in 0..n {
            let z = self.first[2] + tz;
            for ty in 0..n {
                let y = self.first[1] + ty;
                let wyz = norm * self.gauss[2][tz] * self.gauss[1][ty];
                let ryz = self.dist2[2][tz] + self.dist2[1][ty];
                let row = px[0] * (y + px[1] * z);
                for tx in 0..n {
                    let rho2 = ryz + self.dist2[0][tx];
                    f(
                        row + self.first[0] + tx,
                        wyz * self.gauss[0][tx] * (a0 + a1 * rho2),
                    );
                }
            }
        }
    }
}

/// `out += M^far F` for the spheres `(pos, radius)` whose bounding box starts at `lo`,
/// visited in `order` (all of them, else in index order); `reals` holds [`kernel`].
pub(super) fn far<T: Real>(
    ff: &FreeFast<T>,
    eta: T,
    lo: [f64; 3],
    (pos, radius, order): (&[T::V3], &[T], Option<&[usize]>),
    force: &[T::V3],
    (cx, reals): (&mut [Cx<T>], &mut [T]),
    out: &mut [T::V3],
) {
    let plan = &ff.plan;
    let [mx, my, _] = plan.m;
    let (octant, cloud) = plan.split_reals(reals);
    cloud.fill(T::ZERO);
    let origin = [0, 1, 2].map(|d| lo[d] - ff.reach - ff.h);
    let shape = (ff.sigma, ff.support);
    let index = |k: usize| order.map_or(k, |o| o[k]);
    for k in 0..pos.len() {
        let j = index(k);
        let (p, a) = (pos[j], radius[j]);
        let w = Window::new(ff, origin, T::v3_to_f64(p));
        let f = T::xyz(force[j]).map(|c| c.to_f64());
        let alpha = a.to_f64() * a.to_f64() / 6.0;
        w.visit(shape, alpha, [mx, my], |q, wt| {
            for c in 0..3 {
                cloud[3 * q + c] += T::from_f64(wt * f[c]);
            }
        });
    }
    spectral::convolve(plan, cx, octant, cloud);
    let scale = ff.h * ff.h * ff.h / eta.to_f64();
    for k in 0..pos.len() {
        let i = index(k);
        let (p, a) = (pos[i], radius[i]);
        let w = Window::new(ff, origin, T::v3_to_f64(p));
        let alpha = a.to_f64() * a.to_f64() / 6.0;
        let mut u = [0.0f64; 3];
        w.visit(shape, alpha, [mx, my], |q, wt| {
            for (c, uc) in u.iter_mut().enumerate() {
                *uc += wt * cloud[3 * q + c].to_f64();
            }
        });
        out[i] += T::v3_from(u.map(|c| c * scale));
    }
}
