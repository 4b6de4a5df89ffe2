//! The thermal-noise generator: a seeded xoshiro256++ stream and standard normal
//! deviates by Box–Muller, computed in `f64` with libm.
//!
//! The deviates are computed in `f64` whatever the kernel's precision and rounded once
//! to `T`: the same seed gives the same `f64` deviates on every platform (libm is plain
//! Rust, no platform maths library), and an `f32` run sees exactly those deviates
//! rounded. The generator is the caller's state, like the particles: a
//! [`step`](crate::integrate::step) draws from a copy of [`State::noise`](crate::State::noise) and writes the
//! copy back only when the step succeeds, so a refused step leaves it untouched.
//!
//! A refused step can be retried as `2^depth` shorter steps whose noise refines the
//! refused one's (a Brownian bridge, [`Noise::split`]): the sub-steps' Wiener
//! increments add up to the refused step's increment and are, given it, independent
//! with the bridge's conditional law. Redrawing a fresh increment instead would bias
//! the run against the large kicks that made the step fail.

pub mod lanczos;
pub mod reduced;

use crate::real::Real;

/// A seedable, deterministic source of standard normal deviates.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Noise {
    /// xoshiro256++ state (Blackman and Vigna 2019).
    rng: [u64; 4],
    /// The second deviate of the last Box–Muller pair, as bits (so `Eq` holds).
    spare: Option<u64>,
    /// Sub-step of a split step ([`Noise::split`]); `depth == 0` is a plain generator.
    part: Part,
}

/// Which of the `2^depth` sub-steps of a split step a generator feeds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Part {
    depth: u8,
    index: u32,
}

/// Deepest split [`Noise::split`] accepts (`2^12` sub-steps).
pub const MAX_SPLIT_DEPTH: u8 = 12;

/// `2^-53`: a 53-bit integer times this is a uniform double in `[0, 1)`.
const UNIT: f64 = 1.0 / (1u64 << 53) as f64;

impl Noise {
    /// A generator seeded from `seed`: the xoshiro256++ state is four outputs of
    /// SplitMix64 started at `seed`, as `rand_xoshiro` seeds `seed_from_u64` (the
    /// same stream bit for bit: `tests/kernel/bridge.rs` compares them).
    pub const fn new(seed: u64) -> Self {
        let mut sm = seed;
        let mut rng = [0u64; 4];
        let mut k = 0;
        while k < 4 {
            sm = sm.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = sm;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            rng[k] = z ^ (z >> 31);
            k += 1;
        }
        Self {
            rng,
            spare: None,
            part: Part { depth: 0, index: 0 },
        }
    }

    /// The generator's whole state as six words, for a checkpoint: the four
    /// xoshiro256++ words, then `1` and the spare deviate's bits when a Box–Muller
    /// spare is pending (`0, 0` otherwise). A split sub-step's generator saves as the
    /// plain generator at the same point of the stream ([`Noise::join`]).
    pub fn save(&self) -> [u64; 6] {
        let [a, b, c, d] = self.rng;
        let (flag, spare) = match self.spare {
            Some(bits) => (1, bits),
            None => (0, 0),
        };
        [a, b, c, d, flag, spare]
    }

    /// The generator [`Noise::save`] saved; `None` for words no generator has (an
    /// all-zero xoshiro state, a spare flag other than 0 or 1, or a spare without it).
    pub fn restore(words: [u64; 6]) -> Option<Self> {
        let [a, b, c, d, flag, spare] = words;
        let spare = match (flag, spare) {
            (0, 0) => None,
            (1, bits) => Some(bits),
            _ => return None,
        };
        if a | b | c | d == 0 {
            return None;
        }
        Some(Self {
            rng: [a, b, c, d],
            spare,
            part: Part::default(),
        })
    }

    /// The next 64 random bits (xoshiro256++).
    fn next_u64(&mut self) -> u64 {
        let s = &mut self.rng;
        let out = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        out
    }

    /// The generator of sub-step `index` (`0 .. 2^depth`) when one step of length `dt`
    /// is split into `2^depth` steps of length `dt / 2^depth`, each drawn from a clone
    /// of `self` taken before the step (a Brownian bridge; `depth` is capped at
    /// [`MAX_SPLIT_DEPTH`], `index` taken modulo `2^depth`).
    ///
    /// Its [`Noise::fill`] of `n` vectors first draws the `n` vectors `xi` the unsplit
    /// step would have drawn, then one vector set `eta_q` per node `q` of the binary
    /// tree of halvings (breadth first, `2^depth - 1` sets), and returns the leaf
    /// `index` of the recursion `xi_left = (xi + eta) / sqrt 2`,
    /// `xi_right = (xi - eta) / sqrt 2`. Each leaf is standard normal, the leaves are
    /// independent, and they sum to `2^(depth/2) xi`: the sub-steps' increments
    /// `sqrt(dt / 2^depth) xi_leaf` add up to the unsplit step's `sqrt(dt) xi`.
    ///
    /// Every sub-step draws the whole tree, so the generator a successful last sub-step
    /// leaves, passed through [`Noise::join`], continues after the tree.
    pub fn split(&self, depth: u8, index: u32) -> Self {
        let depth = depth.min(MAX_SPLIT_DEPTH);
        let mut g = self.clone();
        g.part = Part {
            depth,
            index: index & ((1u32 << depth) - 1),
        };
        g
    }

    /// The plain generator that continues where this one is (after the tree of a
    /// split sub-step's draws).
    pub fn join(mut self) -> Self {
        self.part = Part::default();
        self
    }

    /// One uniform deviate in `[0, 1)`: the top 53 bits of the next draw (hosts place
    /// generated scenes with it, from the same seeded stream as the noise).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * UNIT
    }

    /// One standard normal deviate (Box–Muller: `sqrt(-2 ln u1) (cos, sin)(2 pi u2)`,
    /// `u1` in `(0, 1]` so the logarithm is finite; the sine half is kept for the next
    /// call).
    pub fn normal(&mut self) -> f64 {
        if let Some(bits) = self.spare.take() {
            return f64::from_bits(bits);
        }
        let u1 = ((self.next_u64() >> 11) + 1) as f64 * UNIT;
        let u2 = (self.next_u64() >> 11) as f64 * UNIT;
        let r = libm::sqrt(-2.0 * libm::log(u1));
        let phase = 2.0 * core::f64::consts::PI * u2;
        self.spare = Some((r * libm::sin(phase)).to_bits());
        r * libm::cos(phase)
    }

    /// Fills `out` with independent standard normal vectors, bead by bead (x, y, z);
    /// for a split generator, with its leaf of the bridge ([`Noise::split`]).
    pub fn fill<T: Real>(&mut self, out: &mut [T::V3]) {
        self.fill_parts::<T>(out, &mut []);
    }

    /// [`Noise::fill`] of `head` followed by `tail` as one sequence: `head`'s vectors,
    /// then `tail` three values at a time (its real parts, the imaginary parts set to
    /// zero; a `tail` not a multiple of three leaves its last values as they were).
    /// For a split generator the bridge runs over the whole sequence, so that the
    /// leaves of both parts add up to the unsplit draw (PSE's noise: the real part's
    /// vectors, then the white noise on the wave grid).
    pub fn fill_parts<T: Real>(&mut self, head: &mut [T::V3], tail: &mut [[T; 2]]) {
        let n = head.len();
        let count = n + tail.len() / 3;
        // Writes (`sign` None) or mixes (`sign` the path's half) the `k`-th vector.
        let mut put = |k: usize, x: [f64; 3], sign: Option<T>, root: T| match (k < n, sign) {
            (true, None) => head[k] = T::v3_from(x),
            (true, Some(s)) => head[k] = (head[k] + T::v3_from(x) * s) * root,
            (false, _) => {
                for (c, &x) in x.iter().enumerate() {
                    let v = &mut tail[3 * (k - n) + c];
                    v[0] = match sign {
                        None => T::from_f64(x),
                        Some(s) => (v[0] + T::from_f64(x) * s) * root,
                    };
                    v[1] = T::ZERO;
                }
            }
        };
        for k in 0..count {
            put(k, self.vector(), None, T::ONE);
        }
        let Part { depth, index } = self.part;
        let root = T::from_f64(core::f64::consts::FRAC_1_SQRT_2);
        for level in 1..=depth {
            // The node on the path at the level above, and which half the path takes.
            let parent = index >> (depth - level + 1);
            let sign = if (index >> (depth - level)) & 1 == 0 {
                T::ONE
            } else {
                -T::ONE
            };
            for node in 0..1u32 << (level - 1) {
                for k in 0..count {
                    let eta = self.vector();
                    if node == parent {
                        put(k, eta, Some(sign), root);
                    }
                }
            }
        }
    }

    fn vector(&mut self) -> [f64; 3] {
        let x = self.normal();
        let y = self.normal();
        let z = self.normal();
        [x, y, z]
    }
}
