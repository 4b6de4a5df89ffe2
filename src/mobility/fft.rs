//! A `no_std` mixed-radix (2, 3, 4, 5) FFT over caller storage, for the grids of PSE
//! (`mobility/pse.rs`) and of the fast free-space product (`mobility/free_fast.rs`).
//!
//! Why our own and not rustfft: the kernel promises the same bits on x86_64, aarch64 and
//! the M4, with no `unsafe`. rustfft chooses SIMD code paths at run time (so the bits
//! can differ between machines) and is built on `unsafe`. This one is plain scalar
//! arithmetic in a fixed order (Stockham autosort, Govindaraju et al. 2008
//! formulation), twiddles from `libm` in f64: the same bits everywhere.
//!
//! A 3D transform runs axis by axis; the lines of an axis are gathered [`CHUNK`] at a
//! time into a small contiguous scratch (element `j` of line `c` at `j * CHUNK + c`), so
//! each butterfly's inner loop runs over contiguous memory whatever the axis' stride,
//! and the scratch is `2 CHUNK max(M)` values, not a second grid.

use crate::real::Real;

/// A complex number, `[re, im]`.
pub type Cx<T> = [T; 2];

/// Lines transformed together (the scratch's width).
pub(crate) const CHUNK: usize = 32;

/// At most this many radix stages (a length below `4^16`).
const MAX_STAGES: usize = 24;

/// The radix stages of a length, largest first: 4s, then a 2, then 3s and 5s.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Factors {
    radix: [u8; MAX_STAGES],
    count: usize,
}

impl Factors {
    /// `None` unless `n >= 1` is `2^a 3^b 5^c`.
    pub(crate) fn new(mut n: usize) -> Option<Self> {
        let mut f = Self {
            radix: [0; MAX_STAGES],
            count: 0,
        };
        for r in [4usize, 2, 3, 5] {
            while n.is_multiple_of(r) && n > 1 {
                if f.count == MAX_STAGES {
                    return None;
                }
                f.radix[f.count] = r as u8;
                f.count += 1;
                n /= r;
            }
        }
        (n == 1).then_some(f)
    }
}

/// The smallest even `2^a 3^b 5^c` at least `n` (at least 2).
pub fn good_size(n: usize) -> usize {
    let mut m = n.max(2);
    loop {
        if m.is_multiple_of(2) && Factors::new(m).is_some() {
            return m;
        }
        m += 1;
    }
}

/// `tw[t] = exp(-2 pi i t / n)`, `t < n`, each from `libm` in f64 (no recurrence, so
/// no drift).
pub(crate) fn twiddles<T: Real>(n: usize, tw: &mut [Cx<T>]) {
    for (t, w) in tw[..n].iter_mut().enumerate() {
        let a = -2.0 * core::f64::consts::PI * (t as f64) / (n as f64);
        *w = [T::from_f64(libm::cos(a)), T::from_f64(libm::sin(a))];
    }
}

#[inline(always)]
fn mul<T: Real>(a: Cx<T>, b: Cx<T>) -> Cx<T> {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

#[inline(always)]
fn add<T: Real>(a: Cx<T>, b: Cx<T>) -> Cx<T> {
    [a[0] + b[0], a[1] + b[1]]
}

#[inline(always)]
fn sub<T: Real>(a: Cx<T>, b: Cx<T>) -> Cx<T> {
    [a[0] - b[0], a[1] - b[1]]
}

/// `s i a`, `s = -1` forward, `+1` inverse: `(-s im, s re)`.
#[inline(always)]
fn rot<T: Real>(a: Cx<T>, inverse: bool) -> Cx<T> {
    if inverse {
        [-a[1], a[0]]
    } else {
        [a[1], -a[0]]
    }
}

#[inline(always)]
fn scale<T: Real>(a: Cx<T>, s: T) -> Cx<T> {
    [a[0] * s, a[1] * s]
}

/// The length-`R` DFT in place, `X_q = sum_r v_r exp(-+2 pi i r q / R)`.
#[inline(always)]
fn butterfly<T: Real, const R: usize>(v: &mut [Cx<T>; R], inverse: bool) {
    let c = T::from_f64;
    match R {
        2 => {
            let (a, b) = (v[0], v[1]);
            (v[0], v[1]) = (add(a, b), sub(a, b));
        }
        3 => {
            let s = add(v[1], v[2]);
            let t = sub(v[0], scale(s, T::HALF));
            let u = scale(rot(sub(v[1], v[2]), inverse), c(0.866_025_403_784_438_6));
            (v[0], v[1], v[2]) = (add(v[0], s), add(t, u), sub(t, u));
        }
        4 => {
            let (t0, t1) = (add(v[0], v[2]), sub(v[0], v[2]));
            let (t2, t3) = (add(v[1], v[3]), rot(sub(v[1], v[3]), inverse));
            (v[0], v[1], v[2], v[3]) = (add(t0, t2), add(t1, t3), sub(t0, t2), sub(t1, t3));
        }
        _ => {
            // R = 5: cos and sin of 2 pi / 5 and 4 pi / 5.
            let (c1, c2) = (c(0.309_016_994_374_947_45), c(-0.809_016_994_374_947_5));
            let (s1, s2) = (c(0.951_056_516_295_153_5), c(0.587_785_252_292_473_1));
            let (a1, b1) = (add(v[1], v[4]), sub(v[1], v[4]));
            let (a2, b2) = (add(v[2], v[3]), sub(v[2], v[3]));
            let p1 = add(v[0], add(scale(a1, c1), scale(a2, c2)));
            let p2 = add(v[0], add(scale(a1, c2), scale(a2, c1)));
            let q1 = rot(add(scale(b1, s1), scale(b2, s2)), inverse);
            let q2 = rot(sub(scale(b1, s2), scale(b2, s1)), inverse);
            v[0] = add(v[0], add(a1, a2));
            (v[1], v[4]) = (add(p1, q1), sub(p1, q1));
            (v[2], v[3]) = (add(p2, q2), sub(p2, q2));
        }
    }
}

/// One Stockham stage of radix `R` from `x` to `y` (length `n`, `batch` lines
/// interleaved), after stages whose radices multiply to `ns`.
#[allow(clippy::too_many_arguments)]
fn stage<T: Real, const R: usize>(
    x: &[Cx<T>],
    y: &mut [Cx<T>],
    n: usize,
    batch: usize,
    ns: usize,
    tw: &[Cx<T>],
    inverse: bool,
) {
    let m = n / R;
    let step = n / (ns * R);
    let mut v = [[[T::ZERO; 2]; R]; CHUNK];
    let v = &mut v[..batch];
    for j in 0..m {
        let k = j % ns;
        let dst = (j / ns) * ns * R + k;
        let mut w = [[T::ONE, T::ZERO]; R];
        for (q, wq) in w.iter_mut().enumerate().skip(1) {
            let t = tw[q * k * step];
            *wq = if inverse { [t[0], -t[1]] } else { t };
        }
        // Whole rows of `batch` values at a time: slices, so no per-value index checks.
        for q in 0..R {
            let src = &x[(j + q * m) * batch..(j + q * m + 1) * batch];
            for (vc, &xc) in v.iter_mut().zip(src) {
                vc[q] = if q == 0 { xc } else { mul(xc, w[q]) };
            }
        }
        for vc in v.iter_mut() {
            butterfly::<T, R>(vc, inverse);
        }
        for q in 0..R {
            let d = &mut y[(dst + q * ns) * batch..(dst + q * ns + 1) * batch];
            for (dc, vc) in d.iter_mut().zip(v.iter()) {
                *dc = vc[q];
            }
        }
    }
}

/// The transform of `batch` interleaved lines of length `n` held in `a`; `b` is the
/// ping-pong buffer. Returns whether the result ended in `b`.
pub(crate) fn transform<T: Real>(
    a: &mut [Cx<T>],
    b: &mut [Cx<T>],
    n: usize,
    batch: usize,
    f: &Factors,
    tw: &[Cx<T>],
    inverse: bool,
) -> bool {
    let mut ns = 1;
    let mut in_b = false;
    for &r in &f.radix[..f.count] {
        let (x, y): (&[Cx<T>], &mut [Cx<T>]) = if in_b { (b, a) } else { (a, b) };
        match r {
            2 => stage::<T, 2>(x, y, n, batch, ns, tw, inverse),
            3 => stage::<T, 3>(x, y, n, batch, ns, tw, inverse),
            4 => stage::<T, 4>(x, y, n, batch, ns, tw, inverse),
            _ => stage::<T, 5>(x, y, n, batch, ns, tw, inverse),
        }
        ns *= r as usize;
        in_b = !in_b;
    }
    in_b
}

/// A 3D grid's shape for the transform: points per axis, their radix stages, and the
/// number of interleaved components per point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid3 {
    pub(crate) m: [usize; 3],
    pub(crate) factors: [Factors; 3],
    pub(crate) comps: usize,
}

impl Grid3 {
    /// Scratch values [`fft3`] needs: two buffers of [`CHUNK`] lines of the longest axis.
    pub(crate) fn scratch_len(&self) -> usize {
        2 * CHUNK * self.m[0].max(self.m[1]).max(self.m[2])
    }
}

/// The unnormalised DFT (forward `exp(-i k.x)`, inverse `exp(+i k.x)`) along `axes`
/// (of `x`, `y`, `z`, in that order) of every component of `grid` (point
/// `x + M_x (y + M_y z)`, component `c` at `comps * point + c`); lines in a fixed order,
/// each line's arithmetic its own (so slabs of planes transformed apart along `x` and
/// `y` give the same bits). `tw[d]`
/// holds [`twiddles`] for `M_d`; `scratch` at least [`Grid3::scratch_len`].
pub(crate) fn fft3<T: Real>(
    g: &Grid3,
    grid: &mut [Cx<T>],
    scratch: &mut [Cx<T>],
    tw: [&[Cx<T>]; 3],
    inverse: bool,
    axes: core::ops::Range<usize>,
) {
    let [mx, my, mz] = g.m;
    let stride = [1, mx, mx * my];
    for d in axes {
        let n = g.m[d];
        if n == 1 {
            continue;
        }
        // The line starts: every point with coordinate d = 0, in ascending order.
        let (o1, o2) = match d {
            0 => ((my, mx), (mz, mx * my)),
            1 => ((mx, 1), (mz, mx * my)),
            _ => ((mx, 1), (my, mx)),
        };
        let (a, rest) = scratch.split_at_mut(CHUNK * n);
        let b = &mut rest[..CHUNK * n];
        let mut starts = [0usize; CHUNK];
        let mut filled = 0;
        let total = o1.0 * o2.0 * g.comps;
        for line in 0..total {
            let c = line % g.comps;
            let p = line / g.comps;
            let (i1, i2) = (p % o1.0, p / o1.0);
            starts[filled] = (i1 * o1.1 + i2 * o2.1) * g.comps + c;
            filled += 1;
            if filled == CHUNK || line + 1 == total {
                let st = g.comps * stride[d];
                let batch = filled;
                for (c, &s) in starts[..batch].iter().enumerate() {
                    for j in 0..n {
                        a[j * batch + c] = grid[s + j * st];
                    }
                }
                let in_b = transform(a, b, n, batch, &g.factors[d], tw[d], inverse);
                let out: &[Cx<T>] = if in_b { b } else { a };
                for (c, &s) in starts[..batch].iter().enumerate() {
                    for j in 0..n {
                        grid[s + j * st] = out[j * batch + c];
                    }
                }
                filled = 0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the direct DFT, every length 2..=64 that factors and a few larger,
    /// forward and inverse, on a batch of 3 lines.
    #[test]
    fn matches_direct_dft() {
        let extra = [90, 128, 150, 243, 250];
        for n in (1..=64).chain(extra) {
            let Some(f) = Factors::new(n) else { continue };
            let mut tw = [[0.0f64; 2]; 250];
            twiddles(n, &mut tw);
            for inverse in [false, true] {
                let batch = 3;
                let mut x = [[0.0f64; 2]; 750];
                for (i, v) in x[..n * batch].iter_mut().enumerate() {
                    *v = [
                        ((i * 7 + 3) % 11) as f64 - 5.0,
                        ((i * 5 + 1) % 13) as f64 - 6.0,
                    ];
                }
                let (mut a, mut b) = (x, [[0.0; 2]; 750]);
                let in_b = transform(
                    &mut a[..n * batch],
                    &mut b[..n * batch],
                    n,
                    batch,
                    &f,
                    &tw,
                    inverse,
                );
                let out = if in_b { &b } else { &a };
                let sign = if inverse { 1.0 } else { -1.0 };
                for c in 0..batch {
                    for q in 0..n {
                        let (mut re, mut im) = (0.0, 0.0);
                        for r in 0..n {
                            let t = sign * 2.0 * core::f64::consts::PI * ((r * q) % n) as f64
                                / n as f64;
                            let v = x[r * batch + c];
                            let (sn, cs) = (libm::sin(t), libm::cos(t));
                            re += v[0] * cs - v[1] * sn;
                            im += v[0] * sn + v[1] * cs;
                        }
                        let o = out[q * batch + c];
                        let err = (o[0] - re).abs().max((o[1] - im).abs());
                        assert!(err < 1e-12 * n as f64 * 10.0, "n {n} q {q}: {err:e}");
                    }
                }
            }
        }
    }

    #[test]
    fn good_sizes() {
        assert_eq!(good_size(1), 2);
        assert_eq!(good_size(7), 8);
        assert_eq!(good_size(11), 12);
        assert_eq!(good_size(13), 16);
        assert_eq!(good_size(61), 64);
        assert_eq!(good_size(97), 100);
        assert_eq!(good_size(121), 128);
    }
}
