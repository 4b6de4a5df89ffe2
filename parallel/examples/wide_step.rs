//! A small step run plainly and inside a function compiled with AVX2 enabled (runtime
//! selection of a whole step): the time per step both ways and whether the
//! positions keep their bits.
//!
//! `cargo run --release -p hydrorattle-parallel --example wide_step -- [N] [STEPS] [ROUNDS]`
//! (defaults 25, 2000, 5): an N-bead settling helix (radius-1 beads, bonds of length 3),
//! deterministic Overdamped `f64` steps, dt = 0.01, on one thread; the best of ROUNDS
//! runs of STEPS steps each way, taken in turn.
//!
//! Only code the optimiser inlines into the `target_feature` function is compiled with
//! AVX2; the step's callees that are not inlined keep the portable build's SSE2. The
//! whole-binary fast build (`.cargo/x86-64-v3.toml`) widens everything.

use std::time::Instant;

mod common;

use hydrorattle::glam::DVec3;
use hydrorattle::{Bond, Layout, NoForce, Params, State, step_slices};
use hydrorattle_heap::Buffers;

/// `steps` steps from `start`; the final positions. (Inlined, so that the AVX2 copy
/// below holds the loop and whatever the optimiser inlines of the step.)
#[inline(always)]
fn run(start: &[DVec3], bonds: &[Bond<f64>], p: &Params<f64>, steps: usize) -> Vec<DVec3> {
    let n = start.len();
    let mut store = Buffers::<f64>::new(Layout::for_params(p, n, bonds.len()));
    let mut ws = store.workspace();
    let (radius, density) = (vec![1.0; n], vec![4.5; n]);
    let mut pos = start.to_vec();
    let (mut vel, mut omega, mut time) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n], 0.0);
    for _ in 0..steps {
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: None,
        };
        step_slices(state, bonds, p, &mut ws, &mut NoForce).expect("step");
    }
    pos
}

/// [`run`] compiled with AVX2. Safety: the CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2(
    start: &[DVec3],
    bonds: &[Bond<f64>],
    p: &Params<f64>,
    steps: usize,
) -> Vec<DVec3> {
    run(start, bonds, p, steps)
}

fn main() {
    let arg = |k: usize, d: usize| {
        std::env::args()
            .nth(k)
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let (n, steps, rounds) = (arg(1, 25), arg(2, 2000), arg(3, 5));
    let start = common::helix(n);
    let bonds = common::chain(&start);
    let p = Params::<f64>::new(0.01);
    let avx2 = hydrorattle_parallel::wide::avx2();
    let (mut best, mut same) = ([f64::INFINITY; 2], true);
    for _ in 0..rounds {
        let t0 = Instant::now();
        let plain = run(&start, &bonds, &p, steps);
        best[0] = best[0].min(t0.elapsed().as_secs_f64());
        if !avx2 {
            continue;
        }
        let t0 = Instant::now();
        // SAFETY: `wide::avx2()` checked that this CPU has AVX2.
        #[cfg(target_arch = "x86_64")]
        let wide = unsafe { run_avx2(&start, &bonds, &p, steps) };
        #[cfg(not(target_arch = "x86_64"))]
        let wide = plain.clone();
        best[1] = best[1].min(t0.elapsed().as_secs_f64());
        same &= plain
            .iter()
            .zip(&wide)
            .all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits));
    }
    let [a, b] = best.map(|s| s / steps as f64 * 1e6);
    println!(
        "N = {n}, {steps} steps, best of {rounds}: portable {a:.2} us/step, AVX2 wrapper {} ({:.3}x), bits {}",
        if avx2 {
            format!("{b:.2} us/step")
        } else {
            "not available".into()
        },
        a / b,
        if same { "identical" } else { "DIFFERENT" }
    );
}
