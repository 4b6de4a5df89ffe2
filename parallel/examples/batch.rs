//! The 25-bead helix step (`bench/peer/helix25.toml`) for `K` systems side by side in
//! the lanes (`hydrorattle_parallel::batch`), against the plain `f64` step (`K = 1`),
//! on one thread, timed in short windows as `host/examples/step_windows.rs` does (the
//! fastest windows are the ones no other process preempted).
//!
//! `cargo run --release -p hydrorattle-parallel --example batch -- [STEPS] [WINDOW] [SWEEP] [K]`
//! (default 20000 steps in windows of 100, sweep `tilt`, every `K`). System `k` of a batch is the
//! scene's helix:
//! * `tilt`: tilted by `0.1 k` rad about the `x` axis (reorientation under gravity
//!   from several starting angles);
//! * `density`: of density `4.5 (1 + k / 4)` (lanes sink at different speeds);
//! * `head`: with head ratio `1.26 + 0.05 k` (other radii and bond lengths);
//! * `same`: the scene in every lane (no lane ever diverges: the lane step's own
//!   speed).
//!
//! Prints, for `K = 1, 2, 4, 8`: microseconds a system-step (best window, median
//! window, and the whole run: the best windows are the ones with the fewest systems
//! stepped alone, so the run's mean is the one that counts the fallbacks), the share of system steps that fell back to their own `f64` step, GFLOP/s
//! at 66.9k flops a system-step (best window, and over the run; docs/BENCHMARKS.md, "The 25-bead step, fourth pass"),
//! the fraction of this build's peak measured in the same run (`examples/peak`'s probe,
//! before and after the timings, the best of both), and each lane's positions digest
//! (lane 0 is the scene itself: its digest is `step_windows`'s after the same steps).

#[path = "../tests/common/helix25.rs"]
mod helix25;
#[path = "../../examples/shared/peak.rs"]
mod peak;

use std::time::Instant;

use hydrorattle::{Layout, NoForce, ParticleSet};
use hydrorattle_heap::Buffers;
use hydrorattle_parallel::batch::{Batch, Lanes};

/// Flops of one system's step (docs/BENCHMARKS.md).
const FLOPS: f64 = 66.9e3;

type Set = ParticleSet<f64, { helix25::N }>;

/// System `k` of `sweep`, and its head ratio.
fn system(sweep: &str, k: usize) -> (Set, f64) {
    let (tilt, density, head) = match sweep {
        "tilt" => (0.1 * k as f64, 4.5, helix25::HEAD_RATIO),
        "density" => (0.0, 4.5 * (1.0 + 0.25 * k as f64), helix25::HEAD_RATIO),
        "head" => (0.0, 4.5, helix25::HEAD_RATIO + 0.05 * k as f64),
        "same" => (0.0, 4.5, helix25::HEAD_RATIO),
        _ => panic!("sweep: tilt, density, head or same"),
    };
    (helix25::beads(tilt, density, head), head)
}

/// Microseconds a system-step (best window, median window, the whole run), the
/// fallback rate, the lanes' digests.
type Run = (f64, f64, f64, f64, Vec<u64>);

/// [`Run`] of `K` systems of `sweep`.
fn run<const K: usize>(sweep: &str, steps: usize, window: usize) -> Run {
    let p = helix25::params();
    let mut sets: [Set; K] = core::array::from_fn(|k| system(sweep, k).0);
    let bonds: [_; K] = core::array::from_fn(|k| helix25::bonds(system(sweep, k).1));
    let layout = Layout::for_params(&p, helix25::N, bonds[0].len());
    let mut one = Buffers::<f64>::new(layout);
    let mut lanes = Buffers::<Lanes<K>>::new(layout);
    let mut batch =
        Batch::<K>::new(helix25::N, bonds.each_ref().map(|b| &b[..]), [&p; K]).expect("batch");
    let windows = (steps / window).max(1);
    let mut per = Vec::with_capacity(windows);
    for _ in 0..windows {
        let t = Instant::now();
        for _ in 0..window {
            if K == 1 {
                // The baseline: the plain f64 step.
                let s = &mut sets[0];
                hydrorattle::step_slices(
                    s.state(),
                    &bonds[0],
                    &p,
                    &mut one.workspace(),
                    &mut NoForce,
                )
                .expect("step");
            } else {
                let r = batch
                    .step(
                        sets.each_mut().map(|s| s.state()),
                        &mut lanes.workspace(),
                        &mut one.workspace(),
                        &mut NoForce,
                    )
                    .expect("batch step");
                r.iter().for_each(|r| {
                    r.as_ref().expect("step");
                });
            }
        }
        per.push(t.elapsed().as_secs_f64() * 1e6 / (window * K) as f64);
    }
    let mean = per.iter().sum::<f64>() / per.len() as f64;
    per.sort_by(f64::total_cmp);
    let digests = sets
        .iter()
        .map(|s| helix25::digest(&s.pos[..helix25::N]))
        .collect();
    let fallback = batch.counts().fallback_rate(K);
    (per[0], per[per.len() / 2], mean, fallback, digests)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: usize, d: usize| args.get(k).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (steps, window) = (arg(1, 20000), arg(2, 100).max(1));
    let sweep = args.get(3).map_or("tilt", String::as_str);
    let build = if cfg!(target_feature = "avx2") {
        "AVX2"
    } else {
        "SSE2"
    };
    let before = peak::f64_peak();
    // A fourth argument runs that `K` alone (for a profiler).
    let only = args.get(4).and_then(|s| s.parse::<usize>().ok());
    let mut results = Vec::new();
    let mut take = |k: usize, f: &dyn Fn() -> Run| {
        if only.is_none_or(|o| o == k) {
            results.push((k, f()));
        }
    };
    take(1, &|| run::<1>(sweep, steps, window));
    take(2, &|| run::<2>(sweep, steps, window));
    take(4, &|| run::<4>(sweep, steps, window));
    take(8, &|| run::<8>(sweep, steps, window));
    let peak = before.max(peak::f64_peak());
    println!(
        "{build} build, sweep {sweep}, {steps} steps in windows of {window}; peak f64 {peak:.1} GFLOP/s (before {before:.1})"
    );
    for (k, (best, median, mean, fallback, digests)) in results {
        let rate = FLOPS / best / 1e3;
        let d: Vec<String> = digests.iter().map(|d| format!("{d:016x}")).collect();
        println!(
            "K = {k}: best {best:.3} us, median {median:.3} us, run {mean:.3} us a system-step; fallback {:.2} %; {rate:.1} GFLOP/s ({:.1} over the run), {:.0} % of the peak; digests {}",
            100.0 * fallback,
            FLOPS / mean / 1e3,
            100.0 * rate / peak,
            d.join(" ")
        );
    }
}
