//! Times one method's step on a 25-bead chain, for profiling (perf, callgrind).
//!
//! `cargo run --profile profiling --example prof -- o|o2|r|s|sp [sweep]` (release
//! code with line tables for the profiler), with `STEPS=n` to set the number of steps
//! (default 20000). Prints microseconds per step and mean constraint iterations; with
//! `HYDRORATTLE_BENCH_MACHINE` set, appends them to `bench/results/helix25.csv`.
#[path = "shared/record.rs"]
mod record;

use glam::DVec3;
use hydrorattle::*;
fn main() {
    let n = 25;
    let mut ps: ParticleSet<f64, 32> = ParticleSet::new();
    for k in 0..n {
        let ph = k as f64;
        ps.push(Particle::new(
            DVec3::new(3.0 * ph.cos(), 3.0 * ph.sin(), 0.5 * ph * 3.0 / 6.0 * 2.0),
            1.0,
            4.5,
        ))
        .unwrap();
    }
    let bonds: BondSet<f64, 32> = BondSet::chain(&ps.pos[..n]).unwrap();
    let mut p = Params::new(0.001);
    p.allow_overlap = true;
    let method = std::env::args().nth(1).unwrap_or("o".into());
    p.method = match method.as_str() {
        "o" => Method::Overdamped,
        "o2" => Method::Overdamped2,
        "r" => Method::Rattle,
        "s" => Method::RattleStable,
        _ => Method::Springs,
    };
    let sweep = std::env::args().nth(2).as_deref() == Some("sweep");
    if sweep {
        p.solver.kind = SolverKind::Sweep;
    }
    let mut ws_store = hydrorattle_heap::Buffers::<f64>::new(hydrorattle::Layout::all(32, 32));
    let mut ws = ws_store.workspace();
    let steps: usize = std::env::var("STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20000);
    let t0 = std::time::Instant::now();
    let mut its = 0;
    for _ in 0..steps {
        its += step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap()
            .iterations;
    }
    let (us, mean) = (
        t0.elapsed().as_secs_f64() * 1e6 / steps as f64,
        its as f64 / steps as f64,
    );
    println!("{method}: {us:.2} us/step its {mean:.2}");
    let solver = if sweep { " sweep" } else { "" };
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "helix25",
        format!("STEPS={steps} cargo run --profile profiling --example prof -- {method}{solver}"),
    );
    let table = format!("one method's step, 25-bead chain, f64, mean of {steps} steps");
    let case = format!("{:?}{solver}", p.method);
    rows.row(&table, &case, "us a step", &format!("{us:.2} us"));
    rows.row(
        &table,
        &case,
        "constraint iterations",
        &format!("{mean:.2}"),
    );
    rows.finish()
        .expect("appending to bench/results/helix25.csv");
}
