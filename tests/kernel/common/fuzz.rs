//! The tests' one deterministic generator (SplitMix64) and the fuzzers' settings,
//! shared by the kernel's tests and, included by path, by the test binaries of the
//! host library, the command line and the thread pool (`host/tests/host/main.rs`,
//! `host-demo/tests/cli/main.rs`, `parallel/tests/parallel/main.rs`).
#![allow(dead_code)]

/// SplitMix64: a tiny deterministic generator, the same stream on every platform.
pub struct Rng(pub u64);

impl Rng {
    /// The generator of case `k` of a run seeded with `seed`.
    pub fn case(seed: u64, k: u64) -> Self {
        Rng(seed.wrapping_add(k.wrapping_mul(0x2545_F491_4F6C_DD1D)))
    }

    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (0 for `n = 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// A uniform number in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniform number in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// A uniform direction (rejection from the cube).
    pub fn direction(&mut self) -> [f64; 3] {
        loop {
            let v = [0; 3].map(|_| self.range(-1.0, 1.0));
            let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if n2 > 1e-4 && n2 <= 1.0 {
                let s = 1.0 / n2.sqrt();
                return v.map(|x| x * s);
            }
        }
    }
}

/// The number of cases (`FUZZ_CASES`, default 100 000) and the seed (`FUZZ_SEED`,
/// default `seed`).
pub fn settings(seed: u64) -> (u64, u64) {
    let var = |name: &str| std::env::var(name).ok().and_then(|s| s.parse().ok());
    (
        var("FUZZ_CASES").unwrap_or(100_000),
        var("FUZZ_SEED").unwrap_or(seed),
    )
}

/// Prints the counts of a fuzz run and fails it on any broken promise.
pub fn report(name: &str, cases: u64, seed: u64, accepted: u64, failures: &[String]) {
    eprintln!(
        "{name}: {cases} cases (seed {seed:#x}): {accepted} accepted, {} refused, {} broken promises",
        cases - accepted - failures.len() as u64,
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {cases} cases broke a promise; first: {:?}",
        failures.len(),
        &failures[..failures.len().min(3)]
    );
}
