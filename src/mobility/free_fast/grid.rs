//! The far part on the grid: spreading with the sphere factor, the aperiodic
//! convolution by zero padding, and interpolation.
//!
//! The cloud's grid (`m` points per axis from the bounding box's lower corner, less the
//! window's reach) sits in the corner of the padded transform (`P >= 2 m` per axis). The
//! kernel is sampled at the offsets `-(m - 1) ..= m - 1` per axis and is zero at the
//! others, so the circular convolution of the padded grid is the aperiodic one; being
//! even in every axis, its transform is real (6 symmetric components kept as reals).

use super::{FreeFast, radial};
use crate::mobility::pse::fft::{self, Cx};
use crate::real::Real;

/// Kernel components: `xx, yy, zz, xy, xz, yz`, by pairs of axes.
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// The padded grid, the FFT scratch and the twiddles per axis.
type Parts<'c, T> = (&'c mut [Cx<T>], &'c mut [Cx<T>], [&'c [Cx<T>]; 3]);

/// Twiddles of the padded grid at the end of `cx`; returns the grid, scratch and them.
fn split<'c, T: Real>(ff: &FreeFast<T>, cx: &'c mut [Cx<T>]) -> Parts<'c, T> {
    let [px, py, pz] = ff.grid.m;
    let (grid, rest) = cx.split_at_mut(3 * px * py * pz);
    let (scratch, rest) = rest.split_at_mut(ff.grid.scratch_len());
    let (twx, rest) = rest.split_at_mut(px);
    let (twy, rest) = rest.split_at_mut(py);
    let twz = &mut rest[..pz];
    fft::twiddles(px, twx);
    fft::twiddles(py, twy);
    fft::twiddles(pz, twz);
    (grid, scratch, [twx, twy, twz])
}

/// The kernel's transform into `reals` (6 per padded point), with the quadrature
/// weight `h^3` and the inverse transform's `1 / P^3` folded in (viscosity 1).
pub(super) fn kernel<T: Real>(ff: &FreeFast<T>, cx: &mut [Cx<T>], reals: &mut [T]) {
    let [px, py, pz] = ff.grid.m;
    let points = px * py * pz;
    let (grid, scratch, tws) = split(ff, cx);
    let b = 1.0 / (2.0 * ff.sigma);
    // Hasimoto's factor of the whole split (variance `4 sigma^2`), not the residual's.
    let beta = 2.0 * ff.sigma * ff.sigma;
    let weight = ff.h * ff.h * ff.h / points as f64;
    let offset = |i: usize, d: usize| -> Option<f64> {
        let (p, m) = (ff.grid.m[d], ff.m[d]);
        match i {
            _ if i < m => Some(i as f64),
            _ if i + m > p => Some(i as f64 - p as f64),
            _ => None,
        }
    };
    for half in 0..2 {
        for z in 0..pz {
            for y in 0..py {
                for x in 0..px {
                    let q = x + px * (y + py * z);
                    let v = match (offset(x, 0), offset(y, 1), offset(z, 2)) {
                        (Some(dx), Some(dy), Some(dz)) => {
                            let d = [dx * ff.h, dy * ff.h, dz * ff.h];
                            let u = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                            let (ci, crr) = radial::far(b, beta, (0.0, 0.0), u);
                            let mut v = [0.0; 3];
                            for (c, vc) in v.iter_mut().enumerate() {
                                let (k, l) = PAIRS[3 * half + c];
                                let diag = if k == l { ci } else { 0.0 };
                                *vc = (diag + crr * d[k] * d[l]) * weight;
                            }
                            v
                        }
                        _ => [0.0; 3],
                    };
                    for c in 0..3 {
                        grid[3 * q + c] = [T::from_f64(v[c]), T::ZERO];
                    }
                }
            }
        }
        fft::fft3(&ff.grid, grid, scratch, tws, false, 0..3);
        for q in 0..points {
            for c in 0..3 {
                reals[6 * q + 3 * half + c] = grid[3 * q + c][0];
            }
        }
    }
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

/// `out += M^far F` for the spheres `(pos, radius)` whose bounding box starts at `lo`;
/// `reals` holds [`kernel`].
pub(super) fn far<T: Real>(
    ff: &FreeFast<T>,
    eta: T,
    lo: [f64; 3],
    (pos, radius): (&[T::V3], &[T]),
    force: &[T::V3],
    (cx, reals): (&mut [Cx<T>], &[T]),
    out: &mut [T::V3],
) {
    let [px, py, pz] = ff.grid.m;
    let points = px * py * pz;
    let (grid, scratch, tws) = split(ff, cx);
    grid.fill([T::ZERO; 2]);
    let origin = [0, 1, 2].map(|d| lo[d] - ff.reach - ff.h);
    let shape = (ff.sigma, ff.support);
    for (j, (&p, &a)) in pos.iter().zip(radius).enumerate() {
        let w = Window::new(ff, origin, T::v3_to_f64(p));
        let f = T::xyz(force[j]).map(|c| c.to_f64());
        let alpha = a.to_f64() * a.to_f64() / 6.0;
        w.visit(shape, alpha, [px, py], |q, wt| {
            for c in 0..3 {
                grid[3 * q + c][0] += T::from_f64(wt * f[c]);
            }
        });
    }
    fft::fft3(&ff.grid, grid, scratch, tws, false, 0..3);
    for q in 0..points {
        let k = &reals[6 * q..6 * q + 6];
        let f = [grid[3 * q], grid[3 * q + 1], grid[3 * q + 2]];
        let row = [[k[0], k[3], k[4]], [k[3], k[1], k[5]], [k[4], k[5], k[2]]];
        for (c, r) in row.iter().enumerate() {
            let re = r[0] * f[0][0] + r[1] * f[1][0] + r[2] * f[2][0];
            let im = r[0] * f[0][1] + r[1] * f[1][1] + r[2] * f[2][1];
            grid[3 * q + c] = [re, im];
        }
    }
    fft::fft3(&ff.grid, grid, scratch, tws, true, 0..3);
    let scale = ff.h * ff.h * ff.h / eta.to_f64();
    for (i, (&p, &a)) in pos.iter().zip(radius).enumerate() {
        let w = Window::new(ff, origin, T::v3_to_f64(p));
        let alpha = a.to_f64() * a.to_f64() / 6.0;
        let mut u = [0.0f64; 3];
        w.visit(shape, alpha, [px, py], |q, wt| {
            for (c, uc) in u.iter_mut().enumerate() {
                *uc += wt * grid[3 * q + c][0].to_f64();
            }
        });
        out[i] += T::v3_from(u.map(|c| c * scale));
    }
}
