//! Nanoseconds per packed block of the stored product `y = mu_tt x` and of the fused
//! assembly + product, and of the noise's products on the reduced copy (written on the
//! way, and read back), at the bead counts given.
//!
//! `cargo run --release --example product -- N [REPS]`: the helix of `scale`, the best of
//! `REPS` (default 20) single-thread passes, and a digest of `y` (the same on every
//! build that keeps the arithmetic). With `HYDRORATTLE_BENCH_MACHINE` set, appends its
//! rows to `bench/results/large-n.csv`.
#[path = "shared/record.rs"]
mod record;

use hydrorattle::linalg::tri;
use hydrorattle::mobility::Hydro;
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{assemble, assemble_apply, band_scratch, product};
use hydrorattle::*;
use std::time::Instant;

/// The bits of `y`, folded.
fn digest(y: &[glam::DVec3]) -> u64 {
    let mut h = 0u64;
    for v in y {
        for c in v.to_array() {
            h = h.rotate_left(7) ^ c.to_bits();
        }
    }
    h
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(1024);
    let reps: usize = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(20);
    let mut pos = Vec::new();
    let mut rad = Vec::new();
    for k in 0..n {
        let ph = k as f64 * 0.68;
        pos.push(glam::DVec3::new(
            3.0 * ph.cos(),
            3.0 * ph.sin(),
            0.8 * k as f64,
        ));
        rad.push(if k == 0 { 2f64.cbrt() } else { 1.0 });
    }
    let mut mu = vec![glam::DMat3::ZERO; tri(n)];
    let par = Serial;
    assemble::<f64>(&par, Hydro::Rpy, 1.0, &pos, &rad, &mut mu).unwrap();
    let x: Vec<glam::DVec3> = (0..n)
        .map(|k| glam::DVec3::new((k as f64).sin(), (k as f64 * 0.3).cos(), -1.0))
        .collect();
    let mut y = vec![glam::DVec3::ZERO; n];
    let mut z = vec![glam::DVec3::ZERO; band_scratch(n).max(1)];
    let blocks = tri(n) as f64;
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "large-n",
        format!("cargo run --release --example product -- {n} {reps}"),
    );
    let table = format!("banded product per packed 3x3 block, one thread, best of {reps}");
    // The best of `reps` runs of `f`, printed with the digest of `y` it leaves.
    let mut report = |name: &str, f: &mut dyn FnMut(&mut Vec<glam::DVec3>)| {
        let mut best = f64::MAX;
        for _ in 0..reps {
            let t = Instant::now();
            f(&mut y);
            best = best.min(t.elapsed().as_secs_f64());
        }
        let (ms, ns) = (best * 1e3, best * 1e9 / blocks);
        let h = digest(&y);
        println!("{name} N={n}: {ms:.3} ms, {ns:.2} ns/block, digest {h:016x}");
        let case = format!("{name}, N = {n}");
        rows.row(
            &table,
            &case,
            "ns a block",
            &format!("{ns:.2} ns ({ms:.3} ms)"),
        );
    };
    report("product", &mut |y| {
        product::<f64>(&par, &mu, n, &x, y, &mut z)
    });
    let mut packed = vec![glam::DMat3::ZERO; reduced::slots(n)];
    report("reduced copy_apply", &mut |y| {
        reduced::copy_apply::<f64>(&par, &mu, n, &mut packed, &x, y, &mut z)
    });
    report("reduced apply", &mut |y| {
        reduced::apply::<f64>(&par, &packed, n, &x, y, &mut z)
    });
    let mut z = vec![glam::DVec3::ZERO; band_scratch(n).max(1)];
    report("assemble_apply", &mut |y| {
        let (level, eta) = (Hydro::Rpy, 1.0);
        assemble_apply::<f64>(&par, level, eta, &pos, &rad, &mut mu, &x, y, &mut z).unwrap()
    });
    rows.finish()
        .expect("appending to bench/results/large-n.csv");
}
