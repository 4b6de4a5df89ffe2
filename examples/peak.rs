//! Measures this machine's practical peak floating-point rate for the build it is
//! compiled as (the default: SSE2; the fast build, `--config .cargo/x86-64-v3.toml`:
//! AVX2, docs/BENCHMARKS.md), without FMA either way (Rust fuses nothing it is not
//! told to): independent multiply-adds on data that stays in L1, which the compiler
//! vectorises. Prints GFLOP/s for f64 and f32.
//!
//! `cargo run --release --example peak`

#[path = "shared/peak.rs"]
mod peak;

fn main() {
    let f64_rate = peak::f64_peak();
    let f32_rate = peak::f32_peak();
    println!(
        "peak multiply-add rate, one core: f64 {f64_rate:.2} GFLOP/s, f32 {f32_rate:.2} GFLOP/s"
    );
}
