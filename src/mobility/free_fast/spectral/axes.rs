//! The passes along one axis of the padded grid: the real `x` lines forward (a
//! half-length complex transform and its split into the real line's spectrum) and back,
//! the `y` lines of the spectrum, and the batched line transform ([`lines`]) the `y` and
//! `z` passes share. Each pass runs its lines [`CHUNK`] at a time through one piece's
//! scratch, in a fixed order.

use super::{Plan, Scratch, Tw};
use crate::mobility::fft::{CHUNK, Cx, Factors, transform};
use crate::real::Real;

impl Plan {
    /// The real lines `(c, y, z)`, `c < comps`, `y < lines[0]`, `z < lines[1]`, whose
    /// point `x` is `value(c, x, y, z)` for `x < nx` and zero beyond, transformed along
    /// `x` into `spec` (`comps` values per point, `x` stride 1, `y` stride `hx`, `z`
    /// stride `hx p_y`).
    pub(super) fn x_forward<T: Real>(
        &self,
        (a, b): Scratch<'_, T>,
        tw: Tw<'_, T>,
        spec: &mut [Cx<T>],
        (comps, lines, nx): (usize, [usize; 2], usize),
        value: impl Fn(usize, usize, usize, usize) -> T,
    ) {
        let (h, hx, py) = (self.p[0] / 2, self.hx(), self.p[1]);
        let total = comps * lines[0] * lines[1];
        let [th, tx, _, _] = tw;
        let mut first = 0;
        while first < total {
            let batch = CHUNK.min(total - first);
            let at = |l: usize| {
                let (c, r) = ((first + l) % comps, (first + l) / comps);
                (c, r % lines[0], r / lines[0])
            };
            for j in 0..h {
                for l in 0..batch {
                    let (c, y, z) = at(l);
                    let v = |x: usize| if x < nx { value(c, x, y, z) } else { T::ZERO };
                    a[j * batch + l] = [v(2 * j), v(2 * j + 1)];
                }
            }
            let n = h * batch;
            let in_b = transform(
                &mut a[..n],
                &mut b[..n],
                h,
                batch,
                &self.factors[0],
                th,
                false,
            );
            let out: &[Cx<T>] = if in_b { &*b } else { &*a };
            for k in 0..hx {
                for l in 0..batch {
                    let (c, y, z) = at(l);
                    let zk = out[(k % h) * batch + l];
                    let zc = out[((h - k) % h) * batch + l];
                    // Even points' transform `(Z_k + conj Z_{h-k}) / 2`, odd points'
                    // `(Z_k - conj Z_{h-k}) / 2i`, joined by the twiddle of `p_x`.
                    let e = [(zk[0] + zc[0]) * T::HALF, (zk[1] - zc[1]) * T::HALF];
                    let o = [(zk[1] + zc[1]) * T::HALF, (zc[0] - zk[0]) * T::HALF];
                    let w = tx[k];
                    let x = [
                        e[0] + w[0] * o[0] - w[1] * o[1],
                        e[1] + w[0] * o[1] + w[1] * o[0],
                    ];
                    spec[(k + hx * (y + py * z)) * comps + c] = x;
                }
            }
            first += batch;
        }
    }

    /// The inverse of [`Plan::x_forward`] on the cloud's lines (3 components): `out(c, x,
    /// y, z, value)` for `x < m_x`, unnormalised (`p_x` times the line's values).
    pub(super) fn x_inverse<T: Real>(
        &self,
        (a, b): Scratch<'_, T>,
        tw: Tw<'_, T>,
        (spec, mz): (&[Cx<T>], usize),
        mut out: impl FnMut(usize, T),
    ) {
        let (h, hx, py) = (self.p[0] / 2, self.hx(), self.p[1]);
        let [mx, my, _] = self.m;
        let total = 3 * my * mz;
        let [th, tx, _, _] = tw;
        let mut first = 0;
        while first < total {
            let batch = CHUNK.min(total - first);
            let at = |l: usize| {
                let (c, r) = ((first + l) % 3, (first + l) / 3);
                (c, r % my, r / my)
            };
            for k in 0..h {
                for l in 0..batch {
                    let (c, y, z) = at(l);
                    let row = hx * (y + py * z);
                    let xk = spec[(k + row) * 3 + c];
                    let xc = spec[(h - k + row) * 3 + c];
                    // `Z_k = (X_k + conj X_{h-k}) + i w^{-k} (X_k - conj X_{h-k})`.
                    let s = [xk[0] + xc[0], xk[1] - xc[1]];
                    let d = [xk[0] - xc[0], xk[1] + xc[1]];
                    let w = tx[k];
                    let wd = [w[0] * d[0] + w[1] * d[1], w[0] * d[1] - w[1] * d[0]];
                    a[k * batch + l] = [s[0] - wd[1], s[1] + wd[0]];
                }
            }
            let n = h * batch;
            let in_b = transform(
                &mut a[..n],
                &mut b[..n],
                h,
                batch,
                &self.factors[0],
                th,
                true,
            );
            let res: &[Cx<T>] = if in_b { &*b } else { &*a };
            for j in 0..h {
                for l in 0..batch {
                    let (c, y, z) = at(l);
                    let v = res[j * batch + l];
                    let base = mx * (y + my * z);
                    for (x, v) in [(2 * j, v[0]), (2 * j + 1, v[1])] {
                        if x < mx {
                            out(3 * (x + base) + c, v);
                        }
                    }
                }
            }
            first += batch;
        }
    }

    /// Transforms along `y` the lines `(c, k, z)`, `z < planes`, of `spec` (3 values a
    /// point): point `j` read as `load(c, j)` (`Some((j', sign))`: the value at `j'`
    /// times `sign`; `None`: zero), points `j < keep` written back.
    pub(super) fn y_pass<T: Real>(
        &self,
        scratch: Scratch<'_, T>,
        tw: Tw<'_, T>,
        spec: &mut [Cx<T>],
        (planes, inverse): (usize, bool),
        load: impl Fn(usize, usize) -> Option<(usize, T)>,
        keep: usize,
    ) {
        let (hx, py) = (self.hx(), self.p[1]);
        // Line `l = c + 3 (k + hx z)`: point `j` at `3 (k + hx (j + py z)) + c`.
        let at = |l: usize, j: usize| (l % (3 * hx)) + 3 * hx * (j + py * (l / (3 * hx)));
        let axis = (py, &self.factors[1], tw[2], inverse);
        lines(
            scratch,
            axis,
            3 * hx * planes,
            spec,
            |spec, l, j| {
                load(l % 3, j).map_or([T::ZERO; 2], |(jj, s)| {
                    let v = spec[at(l, jj)];
                    [v[0] * s, v[1] * s]
                })
            },
            keep,
            |spec, l, j, v| spec[at(l, j)] = v,
        );
    }
}

/// Transforms `total` lines of length `n` (the axis' radix stages and twiddles, and the
/// direction), [`CHUNK`] at a time through the scratch: point `j` of line `l` read as
/// `load(data, l, j)`, and points `j < keep` handed to `store(data, l, j, value)`.
pub(super) fn lines<T: Real, D>(
    (a, b): (&mut [Cx<T>], &mut [Cx<T>]),
    (n, f, tw, inverse): (usize, &Factors, &[Cx<T>], bool),
    total: usize,
    mut data: D,
    load: impl Fn(&D, usize, usize) -> Cx<T>,
    keep: usize,
    mut store: impl FnMut(&mut D, usize, usize, Cx<T>),
) {
    let mut first = 0;
    while first < total {
        let batch = CHUNK.min(total - first);
        for j in 0..n {
            for l in 0..batch {
                a[j * batch + l] = load(&data, first + l, j);
            }
        }
        let len = n * batch;
        let in_b = transform(&mut a[..len], &mut b[..len], n, batch, f, tw, inverse);
        let out: &[Cx<T>] = if in_b { &*b } else { &*a };
        for j in 0..keep {
            for l in 0..batch {
                store(&mut data, first + l, j, out[j * batch + l]);
            }
        }
        first += batch;
    }
}
