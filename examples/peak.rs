//! Measures this machine's practical peak floating-point rate for the build the kernel
//! uses (no target-cpu flags: SSE2, no FMA): independent multiply-adds on data that
//! stays in L1, which the compiler vectorises. Prints GFLOP/s for f64 and f32.
//!
//! `cargo run --release --example peak`

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

fn main() {
    let f64_rate = rate::<f64, 24>(0.0, black_box(0.999_999), black_box(1e-9));
    let f32_rate = rate::<f32, 48>(0.0, black_box(0.999_9), black_box(1e-7));
    println!(
        "peak multiply-add rate, one core: f64 {f64_rate:.2} GFLOP/s, f32 {f32_rate:.2} GFLOP/s"
    );
}
