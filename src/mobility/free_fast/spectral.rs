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
//!
//! The work is split by concern: this file holds the plan (the padded shape, the
//! storage's layout and its twiddles), `axes.rs` the passes along one axis (the real
//! `x` lines forward and back, the `y` lines, and the batched line transform they share),
//! `convolve.rs` the product's convolution (the `z` lines with the kernel applied), and
//! `octant.rs` the kernel's transform into its octant.

mod axes;
mod convolve;
mod octant;

pub(super) use convolve::convolve;
pub(super) use octant::kernel;

use super::pieces::JOBS;
use crate::mobility::fft::{CHUNK, Cx, Factors, good_size};
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
}
