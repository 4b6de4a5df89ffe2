//! The kernel's transform into its octant: the sampled kernel table mirrored into the
//! padded grid (each component even or odd per axis), forward along `x` and `y` by slabs
//! of the cloud's planes, then along `z` by slabs of `y` frequencies, one octant kept.

use core::convert::Infallible;

use super::axes::lines;
use super::{Parts, Plan, halves};
use crate::mobility::fft::Cx;
use crate::mobility::free_fast::pieces::{fixed, none, pieces, rows};
use crate::parallel::Parallel;
use crate::real::Real;

/// Kernel components: `xx, yy, zz, xy, xz, yz`, by pairs of axes.
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// The kernel's transform into its octant `kernel` (6 per point, `x` fastest, then `z`,
/// then `y`: a piece of `y` frequencies owns a slab), from `table`, which holds `(c_I,
/// c_rr)` of the kernel `(c_I I + c_rr d d^T) weight` at the offsets `(x, y, z) h`, `x <
/// m_x` ... (2 per cloud grid point). The `x` and `y` passes by slabs of the cloud's
/// planes, the `z` lines by slabs of `y` frequencies, each piece through `par`.
pub(in crate::mobility::free_fast) fn kernel<T: Real>(
    plan: &Plan,
    cx: &mut [Cx<T>],
    kernel: &mut [T],
    table: &[T],
    (h, weight): (f64, f64),
    par: &dyn Parallel,
) {
    let Parts {
        spec, scratch, tw, ..
    } = plan.parts(cx);
    let [mx, my, mz] = plan.m;
    let [px, py, pz] = plan.p;
    let hx = plan.hx();
    let [oy, oz] = plan.octant();
    let (h, weight) = (T::from_f64(h), T::from_f64(weight));
    // Component `c` of the half: its axes, and whether it is odd along `d`.
    let odd = |half: usize, c: usize, d: usize| {
        let (k, l) = PAIRS[3 * half + c];
        k != l && (k == d || l == d)
    };
    let mirror = |j: usize, p: usize, m: usize, odd: bool| match j {
        _ if j < m => Some((j, T::ONE)),
        _ if j + m > p => Some((p - j, if odd { -T::ONE } else { T::ONE })),
        _ => None,
    };
    let (plane, each) = (plan.plane(), 2 * plan.scratch());
    for half in 0..2 {
        let cuts = (
            (&mut *spec, &rows(plane) as _),
            (&mut *scratch, &fixed(each) as _),
            none(),
        );
        let _ = pieces(par, mz, cuts, |[z0, z1], sp, scr, _| {
            let value = |c, x, y, z: usize| {
                let Some((ax, sx)) = mirror(x, px, mx, odd(half, c, 0)) else {
                    return T::ZERO;
                };
                let z = z0 + z;
                let t = 2 * (ax + mx * (y + my * z));
                let (ci, crr) = (table[t], table[t + 1]);
                let d = [
                    T::from_f64(ax as f64) * h,
                    T::from_f64(y as f64) * h,
                    T::from_f64(z as f64) * h,
                ];
                let (k, l) = PAIRS[3 * half + c];
                let diag = if k == l { ci } else { T::ZERO };
                (diag + crr * d[k] * d[l]) * weight * sx
            };
            plan.x_forward(halves(scr), tw, sp, (3, [my, z1 - z0], px), value);
            let load_y = |c: usize, j: usize| mirror(j, py, my, odd(half, c, 1));
            plan.y_pass(halves(scr), tw, sp, (z1 - z0, false), load_y, oy);
            Ok::<(), Infallible>(())
        });
        // Along `z`, the lines `(c, k, ky)` of the octant, into `kernel`.
        let spec = &*spec;
        let cuts = (
            (&mut *kernel, &rows(6 * hx * oz) as _),
            (&mut *scratch, &fixed(each) as _),
            none(),
        );
        let _ = pieces(par, oy, cuts, |[y0, y1], kn, scr, _| {
            let at = |l: usize| (l % 3, (l / 3) % hx, y0 + l / (3 * hx));
            let axis = (pz, &plan.factors[2], tw[3], false);
            lines(
                halves(scr),
                axis,
                3 * hx * (y1 - y0),
                (spec, kn),
                |(spec, _), l, j| {
                    let (c, k, ky) = at(l);
                    mirror(j, pz, mz, odd(half, c, 2)).map_or([T::ZERO; 2], |(jj, s)| {
                        let v = spec[3 * (k + hx * (ky + py * jj)) + c];
                        [v[0] * s, v[1] * s]
                    })
                },
                oz,
                |(_, kn), l, kz, v| {
                    let (c, k, ky) = at(l);
                    kn[6 * (k + hx * (kz + oz * (ky - y0))) + 3 * half + c] = v[0];
                },
            );
            Ok::<(), Infallible>(())
        });
    }
}
