//! The product's convolution: the cloud's grid forward along `x` and `y` by slabs of
//! its planes, every `z` line of the spectrum forward, multiplied by the kernel's octant
//! (signs by symmetry) and back in rounds, then `y` and `x` back onto the cloud's points.

use core::convert::Infallible;

use super::{Parts, Plan, ROUND, Scratch, Tw, halves};
use crate::mobility::fft::{CHUNK, Cx, transform};
use crate::mobility::free_fast::pieces::{JOBS, fixed, none, pieces, range, rows};
use crate::parallel::Parallel;
use crate::real::Real;

/// `cloud` (3 reals per cloud grid point, `x` fastest) convolved with the kernel whose
/// octant `kernel` holds ([`kernel`](super::kernel)), in place, unnormalised as the kernel is scaled.
/// The `x` and `y` passes by slabs of the cloud's planes, the `z` lines by rounds
/// ([`z_convolve`]), each piece through `par`.
pub(in crate::mobility::free_fast) fn convolve<T: Real>(
    plan: &Plan,
    cx: &mut [Cx<T>],
    kernel: &[T],
    cloud: &mut [T],
    par: &dyn Parallel,
) {
    let Parts {
        spec,
        scratch,
        zbuf,
        tw,
    } = plan.parts(cx);
    let [mx, my, mz] = plan.m;
    let py = plan.p[1];
    let (plane, each) = (plan.plane(), 2 * plan.scratch());
    {
        let cloud = &*cloud;
        let cuts = (
            (&mut *spec, &rows(plane) as _),
            (&mut *scratch, &fixed(each) as _),
            none(),
        );
        let _ = pieces(par, mz, cuts, |[z0, z1], sp, scr, _| {
            let value = |c, x, y, z| cloud[3 * (x + mx * (y + my * (z0 + z))) + c];
            plan.x_forward(halves(scr), tw, sp, (3, [my, z1 - z0], mx), value);
            let load = |_, j| (j < my).then_some((j, T::ONE));
            plan.y_pass(halves(scr), tw, sp, (z1 - z0, false), load, py);
            Ok::<(), Infallible>(())
        });
    }
    z_convolve(plan, [&mut *spec, &mut *scratch, zbuf], tw, kernel, par);
    let cuts = (
        (spec, &rows(plane) as _),
        (cloud, &rows(3 * mx * my) as _),
        (scratch, &fixed(each) as _),
    );
    let _ = pieces(par, mz, cuts, |[z0, z1], sp, cl, scr| {
        let load = |_, j| Some((j, T::ONE));
        plan.y_pass(halves(scr), tw, sp, (z1 - z0, true), load, my);
        plan.x_inverse(halves(scr), tw, (sp, z1 - z0), |q, v| cl[q] = v);
        Ok::<(), Infallible>(())
    });
}

/// Along `z`, every line of the spectrum: forward, the kernel applied, inverse; the
/// cloud's planes written back. The lines run in rounds of [`ROUND`] per piece: the
/// pieces read the spectrum and keep their lines' results in their share of `zbuf`,
/// then the pieces by planes write the round back.
fn z_convolve<T: Real>(
    plan: &Plan,
    [spec, scratch, zbuf]: [&mut [Cx<T>]; 3],
    tw: Tw<'_, T>,
    kernel: &[T],
    par: &dyn Parallel,
) {
    let (hx, mz) = (plan.hx(), plan.m[2]);
    let points = hx * plan.p[1];
    let (plane, each, share) = (plan.plane(), 2 * plan.scratch(), plan.round());
    let mut g0 = 0;
    while g0 < points {
        let gn = (JOBS * ROUND).min(points - g0);
        {
            let spec = &*spec;
            let cuts = (
                (&mut *zbuf, &fixed(share) as _),
                (&mut *scratch, &fixed(each) as _),
                none(),
            );
            let _ = pieces(par, gn, cuts, |[a, b], out, scr, _| {
                z_lines(
                    plan,
                    (spec, out),
                    halves(scr),
                    tw[3],
                    kernel,
                    [g0 + a, b - a],
                );
                Ok::<(), Infallible>(())
            });
        }
        let zbuf = &*zbuf;
        let cuts = ((&mut *spec, &rows(plane) as _), none(), none());
        let _ = pieces(par, mz, cuts, |[z0, z1], sp, _, _| {
            for z in z0..z1 {
                for t in 0..JOBS {
                    let [a, b] = range(gn, t);
                    let n = 3 * (b - a);
                    let src = &zbuf[t * share + z * n..][..n];
                    sp[(z - z0) * plane + 3 * (g0 + a)..][..n].copy_from_slice(src);
                }
            }
            Ok::<(), Infallible>(())
        });
        g0 += gn;
    }
}

/// The `z` lines of the points `first .. first + count` (`x + h_x y`) of `spec`: forward,
/// the kernel applied, inverse; the cloud's planes into `out` (plane `z` at `3 count
/// z`, 3 values a point).
fn z_lines<T: Real>(
    plan: &Plan,
    (spec, out): (&[Cx<T>], &mut [Cx<T>]),
    (a, b): Scratch<'_, T>,
    tz: &[Cx<T>],
    kernel: &[T],
    [first, count]: [usize; 2],
) {
    let (hx, [_, py, pz], mz) = (plan.hx(), plan.p, plan.m[2]);
    let oz_n = plan.octant()[1];
    let points = hx * py;
    let per = CHUNK / 3;
    let mut q0 = 0;
    while q0 < count {
        let np = per.min(count - q0);
        let batch = 3 * np;
        let p0 = first + q0;
        for j in 0..pz {
            for l in 0..batch {
                a[j * batch + l] = match j < mz {
                    true => spec[3 * (p0 + points * j) + l],
                    false => [T::ZERO; 2],
                };
            }
        }
        let n = pz * batch;
        let in_b = transform(
            &mut a[..n],
            &mut b[..n],
            pz,
            batch,
            &plan.factors[2],
            tz,
            false,
        );
        let (x, other) = match in_b {
            true => (&mut b[..n], &mut a[..n]),
            false => (&mut a[..n], &mut b[..n]),
        };
        for kz in 0..pz {
            let (oz, sz) = fold(kz, pz);
            for q in 0..np {
                let p = p0 + q;
                let (oy_, sy) = fold(p / hx, py);
                let kq = 6 * (p % hx + hx * (oz + oz_n * oy_));
                let k = &kernel[kq..kq + 6];
                let (kxy, kxz, kyz) = (k[3] * sy, k[4] * sz, k[5] * sy * sz);
                let row = [[k[0], kxy, kxz], [kxy, k[1], kyz], [kxz, kyz, k[2]]];
                let at = kz * batch + 3 * q;
                let f = [x[at], x[at + 1], x[at + 2]];
                for (c, r) in row.iter().enumerate() {
                    x[at + c] = [
                        r[0] * f[0][0] + r[1] * f[1][0] + r[2] * f[2][0],
                        r[0] * f[0][1] + r[1] * f[1][1] + r[2] * f[2][1],
                    ];
                }
            }
        }
        let back = transform(x, other, pz, batch, &plan.factors[2], tz, true);
        let res: &[Cx<T>] = if back { &*other } else { &*x };
        for j in 0..mz {
            out[3 * count * j + 3 * q0..][..batch].copy_from_slice(&res[j * batch..][..batch]);
        }
        q0 += np;
    }
}

/// A frequency `k < p` folded into the octant `0..=p/2`, and the sign an odd component
/// takes there.
fn fold<T: Real>(k: usize, p: usize) -> (usize, T) {
    match k <= p / 2 {
        true => (k, T::ONE),
        false => (p - k, -T::ONE),
    }
}
