//! Measures this machine's practical peak floating-point rate for the build it is
//! compiled as (the default: SSE2; the fast build, `--config .cargo/x86-64-v3.toml`:
//! AVX2, docs/BENCHMARKS.md), without FMA either way (Rust fuses nothing it is not
//! told to): independent multiply-adds on data that stays in L1, which the compiler
//! vectorises. Prints GFLOP/s for f64 and f32.
//!
//! `cargo run --release --example peak` (with `HYDRORATTLE_BENCH_MACHINE` set, it appends
//! its rows to `bench/results/helix25.csv`)

#[path = "shared/record.rs"]
mod record;

use std::hint::black_box;
use std::time::Instant;

fn rate<T, const L: usize>(zero: T, a: T, b: T) -> f64
where
    T: Copy + std::ops::Mul<Output = T> + std::ops::Add<Output = T>,
{
    // L independent chains held in registers: enough parallelism to hide the latency
    // of the multiply and the add, no loads or stores in the loop.
    let reps = 20_000_000;
    let mut best = f64::INFINITY;
    let mut y = [zero; L];
    for _ in 0..5 {
        y = black_box([zero; L]);
        let t = Instant::now();
        for _ in 0..reps {
            for v in y.iter_mut() {
                *v = *v * a + b;
            }
        }
        black_box(&y);
        best = best.min(t.elapsed().as_secs_f64());
    }
    black_box(&y);
    (2.0 * L as f64 * reps as f64) / best / 1e9
}

/// Independent `f64` chains: twelve registers' worth of lanes (two lanes each with SSE2,
/// four with AVX), enough to hide a multiply's and an add's latency on two pipes each,
/// few enough to stay in the sixteen registers.
const CHAINS: usize = if cfg!(target_feature = "avx") { 48 } else { 24 };

fn main() {
    let f64_rate = rate::<f64, CHAINS>(0.0, black_box(0.999_999), black_box(1e-9));
    let f32_rate = rate::<f32, { 2 * CHAINS }>(0.0, black_box(0.999_9), black_box(1e-7));
    println!(
        "peak multiply-add rate, one core: f64 {f64_rate:.2} GFLOP/s, f32 {f32_rate:.2} GFLOP/s"
    );
    let build = if cfg!(target_feature = "avx2") {
        "fast (AVX2)"
    } else {
        "default (SSE2)"
    };
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "helix25",
        "cargo run --release --example peak".into(),
    );
    let table = "practical peak multiply-add rate, one core, no FMA";
    for (precision, rate) in [("f64", f64_rate), ("f32", f32_rate)] {
        rows.row(table, build, precision, &format!("{rate:.2} GFLOP/s"));
    }
    rows.finish()
        .expect("appending to bench/results/helix25.csv");
}
