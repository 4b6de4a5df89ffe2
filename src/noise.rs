//! The thermal-noise generator: a seeded xoshiro256++ stream and standard normal
//! deviates by Box–Muller, computed in `f64` with libm.
//!
//! The deviates are computed in `f64` whatever the kernel's precision and rounded once
//! to `T`: the same seed gives the same `f64` deviates on every platform (libm is plain
//! Rust, no platform maths library), and an `f32` run sees exactly those deviates
//! rounded. The generator is the caller's state, like the particles: a
//! [`step_thermal`](crate::integrate::step_thermal) draws from a copy and writes the
//! copy back only when the step succeeds, so a refused step leaves it untouched.

use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::real::Real;

/// A seedable, deterministic source of standard normal deviates.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Noise {
    rng: Xoshiro256PlusPlus,
    /// The second deviate of the last Box–Muller pair, as bits (so `Eq` holds).
    spare: Option<u64>,
}

/// `2^-53`: a 53-bit integer times this is a uniform double in `[0, 1)`.
const UNIT: f64 = 1.0 / (1u64 << 53) as f64;

impl Noise {
    /// A generator seeded from `seed` (xoshiro256++ state filled by SplitMix64, as
    /// `rand_xoshiro` does for `seed_from_u64`).
    pub fn new(seed: u64) -> Self {
        Self {
            rng: Xoshiro256PlusPlus::seed_from_u64(seed),
            spare: None,
        }
    }

    /// One standard normal deviate (Box–Muller: `sqrt(-2 ln u1) (cos, sin)(2 pi u2)`,
    /// `u1` in `(0, 1]` so the logarithm is finite; the sine half is kept for the next
    /// call).
    pub fn normal(&mut self) -> f64 {
        if let Some(bits) = self.spare.take() {
            return f64::from_bits(bits);
        }
        let u1 = ((self.rng.next_u64() >> 11) + 1) as f64 * UNIT;
        let u2 = (self.rng.next_u64() >> 11) as f64 * UNIT;
        let r = libm::sqrt(-2.0 * libm::log(u1));
        let phase = 2.0 * core::f64::consts::PI * u2;
        self.spare = Some((r * libm::sin(phase)).to_bits());
        r * libm::cos(phase)
    }

    /// Fills `out` with independent standard normal vectors, bead by bead (x, y, z).
    pub fn fill<T: Real>(&mut self, out: &mut [T::V3]) {
        for v in out {
            let x = self.normal();
            let y = self.normal();
            let z = self.normal();
            *v = T::v3_from([x, y, z]);
        }
    }
}
