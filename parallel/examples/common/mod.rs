//! What the examples share: the bench helix, the step modes of `speedup` and `stages`,
//! and the process's CPU time.

#![allow(dead_code)] // Each example uses a part.

pub mod timed;

use hydrorattle::glam::DVec3;
use hydrorattle::{Bond, Brownian, Params};

/// `n` radius-1 beads on a helix (radius 3, rise 2.5 per bead), three apart.
pub fn helix(n: usize) -> Vec<DVec3> {
    let phi = 2.0 * ((9.0f64 - 6.25).sqrt() / 6.0).asin();
    (0..n)
        .map(|k| {
            let a = phi * k as f64;
            DVec3::new(3.0 * a.cos(), 3.0 * a.sin(), 2.5 * k as f64)
        })
        .collect()
}

/// The bonds of the chain through `start` in order, at their lengths there.
pub fn chain(start: &[DVec3]) -> Vec<Bond<f64>> {
    (1..start.len())
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: (start[i] - start[i - 1]).length(),
        })
        .collect()
}

/// The parameters of a step MODE (`dt` 0.01): `plain` (the defaults), `compact`
/// ([`Params::compact_products`]), `free` ([`Params::matrix_free`]) or `brownian`
/// (kT = 1: midpoint drift, Lanczos noise), `brownian-compact` (that with
/// `compact_products`); exits with a message on another.
pub fn params(mode: &str) -> Params<f64> {
    let mut p = Params::<f64>::new(0.01);
    match mode {
        "plain" => {}
        "compact" => p.compact_products = true,
        "free" => p.matrix_free = true,
        "brownian" => p.brownian = Some(Brownian::new(1.0)),
        "brownian-compact" => {
            p.brownian = Some(Brownian::new(1.0));
            p.compact_products = true;
        }
        other => {
            eprintln!("unknown mode {other:?}: plain, compact, free, brownian or brownian-compact");
            std::process::exit(2);
        }
    }
    p
}

/// Nanoseconds the process's threads have run on a CPU (Linux's
/// `/proc/self/task/*/schedstat`; 0 where `/proc` is absent). On a shared machine the
/// wall clock also counts the time a thread waited for a core; this does not.
pub fn cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// Command-line argument `k` as a number, `d` when absent or not a number.
pub fn arg(k: usize, d: usize) -> usize {
    std::env::args()
        .nth(k)
        .and_then(|s| s.parse().ok())
        .unwrap_or(d)
}
