//! The far part on the grid: spreading with the sphere factor onto the cloud's grid,
//! the aperiodic convolution ([`spectral`]), and interpolation.
//!
//! The cloud's grid has `m` points per axis from the bounding box's lower corner, less
//! the window's reach. The kernel is sampled at the offsets `-(m - 1) ..= m - 1` per
//! axis (smooth, so sampling it is spectrally accurate).

use core::convert::Infallible;

use super::near::Spheres;
use super::pieces::{none, pieces, rows};
use super::{FreeFast, radial, spectral};
use crate::mobility::fft::Cx;
use crate::parallel::Parallel;
use crate::real::Real;

/// The kernel's transform into its octant of `reals`, with the quadrature weight `h^3`
/// and the inverse transform's `1 / P^3` folded in (viscosity 1). The samples by slabs
/// of planes and the transform by pieces ([`spectral::kernel`]), each through `par`: a
/// function of the parameters alone, the same bits on any number of threads.
pub(super) fn kernel<T: Real>(
    ff: &FreeFast<T>,
    cx: &mut [Cx<T>],
    reals: &mut [T],
    par: &dyn Parallel,
) {
    let plan = &ff.plan;
    let [mx, my, mz] = plan.m;
    let points = plan.p.iter().product::<usize>();
    let rad = radial::Radial::new(1.0 / (2.0 * ff.sigma), 2.0 * ff.sigma * ff.sigma);
    let (octant, table) = plan.split_reals(reals);
    let cuts = ((&mut *table, &rows(2 * mx * my) as _), none(), none());
    let _ = pieces(par, mz, cuts, |[z0, z1], tb, _, _| {
        for z in z0..z1 {
            for y in 0..my {
                for x in 0..mx {
                    let d = [x, y, z].map(|i| i as f64 * ff.h);
                    let u = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    // Hasimoto's factor of the whole split (variance `4 sigma^2`), not
                    // the residual's.
                    let (ci, crr) = rad.far((0.0, 0.0), u);
                    let t = 2 * (x + mx * (y + my * (z - z0)));
                    tb[t] = T::from_f64(ci);
                    tb[t + 1] = T::from_f64(crr);
                }
            }
        }
        Ok::<(), Infallible>(())
    });
    let weight = ff.h * ff.h * ff.h / points as f64;
    spectral::kernel(plan, cx, octant, table, (ff.h, weight), par);
}

/// The first grid point of a window along an axis whose grid starts at `origin`.
fn first<T: Real>(ff: &FreeFast<T>, origin: f64, p: f64) -> usize {
    libm::ceil((p - origin - ff.reach) / ff.h).max(0.0) as usize
}

/// One sphere's window: first grid index per axis, the Gaussian factor, the offset
/// from the sphere and its square of each point per axis.
struct Window {
    first: [usize; 3],
    gauss: [[f64; super::MAX_SUPPORT]; 3],
    off: [[f64; super::MAX_SUPPORT]; 3],
    dist2: [[f64; super::MAX_SUPPORT]; 3],
}

impl Window {
    fn new<T: Real>(ff: &FreeFast<T>, origin: [f64; 3], p: [f64; 3]) -> Self {
        let mut w = Self {
            first: [0; 3],
            gauss: [[0.0; super::MAX_SUPPORT]; 3],
            off: [[0.0; super::MAX_SUPPORT]; 3],
            dist2: [[0.0; super::MAX_SUPPORT]; 3],
        };
        let half = 1.0 / (2.0 * ff.sigma * ff.sigma);
        for d in 0..3 {
            let g0 = first(ff, origin[d], p[d]);
            w.first[d] = g0;
            for t in 0..ff.support {
                let x = origin[d] + (g0 + t) as f64 * ff.h - p[d];
                w.off[d][t] = x;
                w.dist2[d][t] = x * x;
                w.gauss[d][t] = libm::exp(-x * x * half);
            }
        }
        w
    }

    /// Calls `f(point, weight, gauss, [ty, tx])` over the window's points in the planes
    /// `z0 .. z1` (`point` counted from plane `z0`), `weight` the Gaussian with the
    /// sphere factor `(1 + alpha lap)`, `gauss` the Gaussian alone (both normalised),
    /// `t` the point's place in the window.
    #[inline(always)]
    fn visit(
        &self,
        (sigma, n): (f64, usize),
        alpha: f64,
        (px, [z0, z1]): ([usize; 2], [usize; 2]),
        mut f: impl FnMut(usize, f64, f64, [usize; 3]),
    ) {
        let s2 = sigma * sigma;
        let norm = libm::pow(2.0 * core::f64::consts::PI * s2, -1.5);
        let (a0, a1) = (1.0 - 3.0 * alpha / s2, alpha / (s2 * s2));
        let fz = self.first[2];
        for tz in z0.saturating_sub(fz)..n.min(z1.saturating_sub(fz)) {
            let z = fz + tz - z0;
            for ty in 0..n {
                let y = self.first[1] + ty;
                let wyz = norm * self.gauss[2][tz] * self.gauss[1][ty];
                let ryz = self.dist2[2][tz] + self.dist2[1][ty];
                let row = px[0] * (y + px[1] * z);
                for tx in 0..n {
                    let rho2 = ryz + self.dist2[0][tx];
                    let g = wyz * self.gauss[0][tx];
                    f(
                        row + self.first[0] + tx,
                        g * (a0 + a1 * rho2),
                        g,
                        [tx, ty, tz],
                    );
                }
            }
        }
    }
}

/// `rows[k] = M^far (F, T)` for sphere `order[k]` ([`Spheres::width`] reals each) for
/// the spheres whose bounding box starts at `lo`, `order` the cell list's (else index
/// order); `reals` holds [`kernel`]. Spreading by slabs of planes (every sphere in
/// order, each adding its terms to the slab's points), the convolution by pieces
/// ([`spectral::convolve`]) and interpolation by rows, each piece through `par`.
///
/// A torque enters as the force density `curl(T g) / 2 = g T x rho / (2 sigma^2)`
/// (`rho` from the sphere to the point), a rotation as the Gaussian's average of half
/// the vorticity, `sum g rho x u / (2 sigma^2)` (by parts).
pub(super) fn far<T: Real>(
    ff: &FreeFast<T>,
    eta: T,
    lo: [f64; 3],
    (s, order): (Spheres<'_, T>, Option<&[usize]>),
    (cx, reals, rows_out): (&mut [Cx<T>], &mut [T], &mut [T]),
    par: &dyn Parallel,
) {
    let Spheres {
        pos,
        radius,
        force,
        torque,
    } = s;
    let plan = &ff.plan;
    let [mx, my, mz] = plan.m;
    let (octant, cloud) = plan.split_reals(reals);
    let origin = [0, 1, 2].map(|d| lo[d] - ff.reach - ff.h);
    let shape = (ff.sigma, ff.support);
    let curl = 1.0 / (2.0 * ff.sigma * ff.sigma);
    let index = |k: usize| order.map_or(k, |o| o[k]);
    let (n, w) = (pos.len(), s.width());
    let cuts = ((&mut *cloud, &rows(3 * mx * my) as _), none(), none());
    let _ = pieces(par, mz, cuts, |[z0, z1], cl, _, _| {
        cl.fill(T::ZERO);
        for k in 0..n {
            let j = index(k);
            let p = T::v3_to_f64(pos[j]);
            let fz = first(ff, origin[2], p[2]);
            if fz >= z1 || fz + ff.support <= z0 {
                continue;
            }
            let win = Window::new(ff, origin, p);
            let f = T::xyz(force[j]).map(|c| c.to_f64());
            let alpha = radius[j].to_f64() * radius[j].to_f64() / 6.0;
            let zs = [z0, z1];
            match torque {
                None => win.visit(shape, alpha, ([mx, my], zs), |q, wt, _, _| {
                    for c in 0..3 {
                        cl[3 * q + c] += T::from_f64(wt * f[c]);
                    }
                }),
                Some(tq) => {
                    let t = T::xyz(tq[j]).map(|c| c.to_f64() * curl);
                    win.visit(shape, alpha, ([mx, my], zs), |q, wt, g, at| {
                        let rho = [0, 1, 2].map(|d| win.off[d][at[d]]);
                        let tr = cross(t, rho);
                        for c in 0..3 {
                            cl[3 * q + c] += T::from_f64(wt * f[c] + g * tr[c]);
                        }
                    })
                }
            }
        }
        Ok::<(), Infallible>(())
    });
    spectral::convolve(plan, cx, octant, cloud, par);
    let scale = ff.h * ff.h * ff.h / eta.to_f64();
    let cloud = &*cloud;
    let cuts = ((&mut rows_out[..w * n], &rows(w) as _), none(), none());
    let _ = pieces(par, n, cuts, |[a, b], r, _, _| {
        for k in a..b {
            let i = index(k);
            let win = Window::new(ff, origin, T::v3_to_f64(pos[i]));
            let alpha = radius[i].to_f64() * radius[i].to_f64() / 6.0;
            let (mut u, mut o) = ([0.0f64; 3], [0.0f64; 3]);
            let all = ([mx, my], [0, mz]);
            match torque {
                None => win.visit(shape, alpha, all, |q, wt, _, _| {
                    for (c, uc) in u.iter_mut().enumerate() {
                        *uc += wt * cloud[3 * q + c].to_f64();
                    }
                }),
                Some(_) => win.visit(shape, alpha, all, |q, wt, g, at| {
                    let v = [0, 1, 2].map(|c| cloud[3 * q + c].to_f64());
                    let rho = [0, 1, 2].map(|d| win.off[d][at[d]]);
                    let rv = cross(rho, v);
                    for c in 0..3 {
                        u[c] += wt * v[c];
                        o[c] += g * rv[c];
                    }
                }),
            }
            let row = &mut r[w * (k - a)..w * (k - a + 1)];
            for c in 0..3 {
                row[c] = T::from_f64(u[c] * scale);
            }
            if torque.is_some() {
                for c in 0..3 {
                    row[3 + c] = T::from_f64(o[c] * scale * curl);
                }
            }
        }
        Ok::<(), Infallible>(())
    });
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
