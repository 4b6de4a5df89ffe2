//! Gaussian spreading onto the grid and interpolation back (the spectral Ewald method of
//! Lindbo & Tornberg, as PSE uses it).
//!
//! Each sphere carries two vector sources, packed as one complex value per component:
//! the force `F_j` (real part) and `a_j^2 F_j` (imaginary part). The wave-space kernel
//! then forms Beenakker's sphere factor `F_j - k^2 a_j^2 F_j / 6` exactly for every
//! radius (`wave.rs`), so polydispersity costs no extra transform: three complex FFTs
//! carry the six real fields. Interpolation reads the real part `U` and the imaginary
//! part `V = IFFT(k^2 u)` and forms `U - a_i^2 V / 6`, the same factor on the receiving
//! sphere. The grand product adds the torque `T_j` as three more components (real
//! parts; six complex values per point), whose real parts come back as the spin field.
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
            let g0 = first_point(pse, p[d], d);
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

/// The (unwrapped) index of a window's first point along axis `d` for the wrapped
/// coordinate `p`: the first above `p - P_d h_d / 2`.
#[inline(always)]
fn first_point<T: Real>(pse: &Pse<T>, p: T, d: usize) -> i64 {
    libm::floor((p / pse.h[d]).to_f64() - 0.5 * pse.support[d] as f64) as i64 + 1
}

/// The planes `z0 .. z0 + nz` of the grid (a slab; the whole grid for interpolation).
#[derive(Clone, Copy)]
pub(super) struct Slab {
    pub(super) z0: usize,
    pub(super) nz: usize,
}

impl Slab {
    #[inline(always)]
    fn holds(&self, iz: usize) -> bool {
        iz >= self.z0 && iz < self.z0 + self.nz
    }
}

/// Calls `f(base, w_yz)` for each `(y, z)` row of a window in `slab` (`base` the row's
/// first point at `x = 0`, counted from the slab's first plane), `z`, then `y`
/// ascending in the window: the fixed order of both spreading and interpolation.
/// Within a row the `x` points follow in window order.
#[inline(always)]
fn rows<T: Real>(pse: &Pse<T>, w: &Window<T>, slab: Slab, mut f: impl FnMut(usize, T)) {
    let [mx, my, _] = pse.grid.m;
    let [_, py, pz] = pse.support;
    for tz in 0..pz {
        let (iz, wz) = (w.index[2][tz], w.weight[2][tz]);
        if !slab.holds(iz) {
            continue;
        }
        for ty in 0..py {
            f(
                (w.index[1][ty] + my * (iz - slab.z0)) * mx,
                w.weight[1][ty] * wz,
            );
        }
    }
}

/// Whether a window of a sphere at `pos` has a plane in `slab` (no weights computed).
#[inline(always)]
fn touches<T: Real>(pse: &Pse<T>, pos: T::V3, slab: Slab) -> bool {
    let (m, support) = (pse.grid.m[2], pse.support[2]);
    if slab.z0 == 0 && slab.nz == m {
        return true;
    }
    let g0 = first_point(pse, T::xyz(pse.cell.wrap_into(pos))[2], 2);
    (0..support as i64).any(|t| slab.holds((g0 + t).rem_euclid(m as i64) as usize))
}

/// The window's `x` points as one contiguous run `(first, count)` when it does not wrap
/// around the box (most windows), else `None`.
#[inline(always)]
fn run<T: Real>(pse: &Pse<T>, w: &Window<T>) -> Option<usize> {
    let (i0, px) = (w.index[0][0], pse.support[0]);
    (i0 + px <= pse.grid.m[0]).then_some(i0)
}

/// The planes `slab` of the grid (`W` components per point, zeroed by the caller) `+=`
/// each sphere's Gaussian times `(F_j, a_j^2 F_j)` packed in the first three components
/// and, for the grand product (`W = 6`), its torque `T_j` in the real parts of the last
/// three; spheres in the order `order` (the cell list's, for cache locality). Every
/// point receives its terms in that order whatever the slab, so slabs in parallel give
/// the bits of the whole grid at once.
pub(super) fn spread<T: Real, const W: usize>(
    pse: &Pse<T>,
    (pos, radius, order): (&[T::V3], &[T], &[usize]),
    (force, torque): (&[T::V3], Option<&[T::V3]>),
    slab: Slab,
    grid: &mut [Cx<T>],
) {
    let px = pse.support[0];
    for &j in order {
        if !touches(pse, pos[j], slab) {
            continue;
        }
        let w = Window::new(pse, pos[j]);
        let a2 = radius[j] * radius[j];
        let v = T::xyz(force[j]).map(|c| [c, a2 * c]);
        let t = torque.map_or([T::ZERO; 3], |t| T::xyz(t[j]));
        let add = |pt: &mut [Cx<T>], s: T| {
            for c in 0..3 {
                pt[c][0] += s * v[c][0];
                pt[c][1] += s * v[c][1];
            }
            for c in 3..W {
                pt[c][0] += s * t[c - 3];
            }
        };
        let wx = &w.weight[0][..px];
        match run(pse, &w) {
            Some(i0) => rows(pse, &w, slab, |base, wyz| {
                let seg = &mut grid[W * (base + i0)..W * (base + i0 + px)];
                for (pt, &x) in seg.chunks_exact_mut(W).zip(wx) {
                    add(pt, x * wyz);
                }
            }),
            None => rows(pse, &w, slab, |base, wyz| {
                for (&i, &x) in w.index[0][..px].iter().zip(wx) {
                    add(&mut grid[W * (base + i)..W * (base + i) + W], x * wyz);
                }
            }),
        }
    }
}

/// `rows[k] = sum_g g(x_g - r_i) (U(x_g) - a_i^2 V(x_g) / 6)` for `i = order[k]`, with
/// `U + i V` the first three components of the grid after the inverse transform (the
/// quadrature weight `h^3` is in the wave-space kernel); for the grand product
/// (`W = 6`) each sphere has two rows, that one and its spin `sum_g g(x_g - r_i)
/// Omega(x_g)`, `Omega` the real parts of the last three components (the rotation
/// blocks carry no sphere factor). Each sphere's sum is its own.
pub(super) fn interpolate<T: Real, const W: usize>(
    pse: &Pse<T>,
    (pos, radius, order): (&[T::V3], &[T], &[usize]),
    grid: &[Cx<T>],
    rows_out: &mut [T::V3],
) {
    let sixth = T::ONE / T::from_f64(6.0);
    let px = pse.support[0];
    let all = Slab {
        z0: 0,
        nz: pse.grid.m[2],
    };
    for (row, &i) in rows_out.chunks_exact_mut(W / 3).zip(order) {
        let w = Window::new(pse, pos[i]);
        let mut acc = [[T::ZERO; 2]; 3];
        let mut spin = [T::ZERO; 3];
        let mut take = |pt: &[Cx<T>], s: T| {
            for c in 0..3 {
                acc[c][0] += s * pt[c][0];
                acc[c][1] += s * pt[c][1];
            }
            for c in 3..W {
                spin[c - 3] += s * pt[c][0];
            }
        };
        let wx = &w.weight[0][..px];
        match run(pse, &w) {
            Some(i0) => rows(pse, &w, all, |base, wyz| {
                let seg = &grid[W * (base + i0)..W * (base + i0 + px)];
                for (pt, &x) in seg.chunks_exact(W).zip(wx) {
                    take(pt, x * wyz);
                }
            }),
            None => rows(pse, &w, all, |base, wyz| {
                for (&j, &x) in w.index[0][..px].iter().zip(wx) {
                    take(&grid[W * (base + j)..W * (base + j) + W], x * wyz);
                }
            }),
        }
        let k = radius[i] * radius[i] * sixth;
        row[0] = T::v3(
            acc[0][0] - k * acc[0][1],
            acc[1][0] - k * acc[1][1],
            acc[2][0] - k * acc[2][1],
        );
        if let Some(r) = row.get_mut(1) {
            *r = T::v3(spin[0], spin[1], spin[2]);
        }
    }
}
