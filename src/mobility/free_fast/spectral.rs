//! The aperiodic convolution on the padded grid by real transforms that touch only the
//! lines that can be non-zero.
//!
//! The cloud's grid holds `m` points per axis in the corner of the padded transform
//! (`p >= 2 m - 1` per axis, so the circular convolution is the aperiodic one). The
//! fields are real, so `x` is transformed real-to-complex: a line of `p_x` reals as
//! `p_x / 2` complex values (even points real, odd imaginary) and one half-length
//! transform, `p_x / 2 + 1` frequencies kept. Of the padded grid's lines only those that
//! meet the cloud are transformed: forward, `x` on the cloud's `m_y m_z` lines, `y` on
//! its `m_z` planes; `z` on every line, the kernel applied and `z` inverted at once, so
//! only the cloud's `m_z` planes are ever stored; then `y` and `x` back on the cloud's
//! lines, and only the cloud's points written. Against the complex transform of the
//! whole padded grid this is about a quarter of the arithmetic and a sixth of the
//! memory.
//!
//! The kernel is even or odd in each axis (`K_kl` odd in `k` and `l` for `k != l`), so
//! its transform is real and one octant of it is kept (the others by sign).
//!
//! Every line's arithmetic is its own and the lines run in a fixed order: the same
//! inputs give the same bits.

use core::convert::Infallible;

use super::pieces::{JOBS, fixed, none, pieces, range, rows};
use crate::mobility::fft::{CHUNK, Cx, Factors, good_size, transform};
use crate::parallel::Parallel;
use crate::real::Real;

/// The padded transform's shape.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plan {
    /// Padded points per axis (`p_x` even).
    pub(super) p: [usize; 3],
    /// The cloud's grid points per axis.
    pub(super) m: [usize; 3],
    /// Radix stages of `p_x / 2`, `p_y`, `p_z`.
    factors: [Factors; 3],
}

/// The parts of the complex storage: spectrum, each piece's two scratch buffers and
/// its share of a round of `z` lines ([`Plan::round`]), twiddles of the half `x`
/// length, of `p_x` (`k <= p_x / 2`), `p_y` and `p_z`.
struct Parts<'c, T> {
    spec: &'c mut [Cx<T>],
    scratch: &'c mut [Cx<T>],
    zbuf: &'c mut [Cx<T>],
    tw: Tw<'c, T>,
}

/// The twiddles.
type Tw<'c, T> = [&'c [Cx<T>]; 4];

/// One piece's scratch: two buffers of [`Plan::scratch`] values.
type Scratch<'s, T> = (&'s mut [Cx<T>], &'s mut [Cx<T>]);

fn halves<T>(s: &mut [Cx<T>]) -> Scratch<'_, T> {
    let n = s.len() / 2;
    s.split_at_mut(n)
}

/// `z` lines per piece and round (a multiple of the batch `CHUNK / 3`).
const ROUND: usize = 4 * (CHUNK / 3);

/// Kernel components: `xx, yy, zz, xy, xz, yz`, by pairs of axes.
pub(super) const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

impl Plan {
    /// The plan for a cloud grid of `m` points per axis (each at least 1); `None` where
    /// a padded length does not factor.
    pub(super) fn new(m: [usize; 3]) -> Option<Self> {
        let p = m.map(|m| good_size(2 * m.max(1) - 1));
        let factors = [
            Factors::new(p[0] / 2)?,
            Factors::new(p[1])?,
            Factors::new(p[2])?,
        ];
        Some(Self { p, m, factors })
    }

    /// Spectral points along `x`.
    fn hx(&self) -> usize {
        self.p[0] / 2 + 1
    }

    /// The kernel octant's points along `y` and `z`.
    fn octant(&self) -> [usize; 2] {
        [self.p[1] / 2 + 1, self.p[2] / 2 + 1]
    }

    /// The cloud's grid points.
    pub(super) fn cloud(&self) -> usize {
        self.m[0] * self.m[1] * self.m[2]
    }

    fn scratch(&self) -> usize {
        CHUNK * (self.p[0] / 2).max(self.p[1]).max(self.p[2])
    }

    /// A piece's share of a round of `z` lines: [`ROUND`] lines of the cloud's planes.
    fn round(&self) -> usize {
        3 * ROUND * self.m[2]
    }

    /// Values of one spectral plane.
    fn plane(&self) -> usize {
        3 * self.hx() * self.p[1]
    }

    /// Complex values needed: the spectrum of the cloud's planes (3 per point), each
    /// piece's scratch and round, and the twiddles.
    pub(super) fn complex_len(&self) -> usize {
        let [px, py, pz] = self.p;
        let pieces = JOBS * (2 * self.scratch() + self.round());
        self.plane() * self.m[2] + pieces + px / 2 + self.hx() + py + pz
    }

    /// Reals needed: the kernel's octant (6 per point) and the cloud's grid (3 per point).
    pub(super) fn reals_len(&self) -> usize {
        let [oy, oz] = self.octant();
        6 * self.hx() * oy * oz + 3 * self.cloud()
    }

    /// Splits `reals` into the kernel's octant and the cloud's grid.
    pub(super) fn split_reals<'r, T>(&self, reals: &'r mut [T]) -> (&'r mut [T], &'r mut [T]) {
        let [oy, oz] = self.octant();
        let (kernel, rest) = reals.split_at_mut(6 * self.hx() * oy * oz);
        (kernel, &mut rest[..3 * self.cloud()])
    }

    fn parts<'c, T: Real>(&self, cx: &'c mut [Cx<T>]) -> Parts<'c, T> {
        let [px, py, pz] = self.p;
        let (spec, rest) = cx.split_at_mut(self.plane() * self.m[2]);
        let (scratch, rest) = rest.split_at_mut(JOBS * 2 * self.scratch());
        let (zbuf, rest) = rest.split_at_mut(JOBS * self.round());
        let (th, rest) = rest.split_at_mut(px / 2);
        let (tx, rest) = rest.split_at_mut(self.hx());
        let (ty, rest) = rest.split_at_mut(py);
        let tz = &mut rest[..pz];
        for (tw, n) in [
            (&mut *th, px / 2),
            (&mut *tx, px),
            (&mut *ty, py),
            (&mut *tz, pz),
        ] {
            for (t, w) in tw.iter_mut().enumerate() {
                let angle = -2.0 * core::f64::consts::PI * (t as f64) / (n as f64);
                *w = [T::from_f64(libm::cos(angle)), T::from_f64(libm::sin(angle))];
            }
        }
        let [th, tx, ty, tz] = [th, tx, ty, tz].map(|t| &*t);
        Parts {
            spec,
            scratch,
            zbuf,
            tw: [th, tx, ty, tz],
        }
    }

    /// The real lines `(c, y, z)`, `c < comps`, `y < lines[0]`, `z < lines[1]`, whose
    /// point `x` is `value(c, x, y, z)` for `x < nx` and zero beyond, transformed along
    /// `x` into `spec` (`comps` values per point, `x` stride 1, `y` stride `hx`, `z`
    /// stride `hx p_y`).
    fn x_forward<T: Real>(
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
    fn x_inverse<T: Real>(
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
    fn y_pass<T: Real>(
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

/// `cloud` (3 reals per cloud grid point, `x` fastest) convolved with the kernel whose
/// octant `kernel` holds ([`kernel`]), in place, unnormalised as the kernel is scaled.
/// The `x` and `y` passes by slabs of the cloud's planes, the `z` lines by rounds
/// ([`z_convolve`]), each piece through `par`.
pub(super) fn convolve<T: Real>(
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

/// The kernel's transform into its octant `kernel` (6 per point, `x` fastest, then `z`,
/// then `y`: a piece of `y` frequencies owns a slab), from `table`, which holds `(c_I,
/// c_rr)` of the kernel `(c_I I + c_rr d d^T) weight` at the offsets `(x, y, z) h`, `x <
/// m_x` ... (2 per cloud grid point). The `x` and `y` passes by slabs of the cloud's
/// planes, the `z` lines by slabs of `y` frequencies, each piece through `par`.
pub(super) fn kernel<T: Real>(
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

/// Transforms `total` lines of length `n` (the axis' radix stages and twiddles, and the
/// direction), [`CHUNK`] at a time through the scratch: point `j` of line `l` read as
/// `load(data, l, j)`, and points `j < keep` handed to `store(data, l, j, value)`.
fn lines<T: Real, D>(
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
