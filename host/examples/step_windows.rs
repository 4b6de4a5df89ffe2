//! A scene's `f64` step timed in short windows on one thread, for a shared machine: the
//! fastest windows are the ones no other process preempted, so their time per step is
//! the step's own (`docs/BENCHMARKS.md`, "The 25-bead step").
//!
//! `cargo run --release -p hydrorattle-host --example step_windows -- SCENE [STEPS] [WINDOW]`
//! (default 20000 steps in windows of 100). Prints the best window and the 10th
//! percentile and median, in microseconds a step, the CPU time a step of the whole run
//! (`/proc/self/stat`'s user + system ticks), and an FNV-1a digest of the final
//! positions' bits, so that builds can be compared. With `HYDRORATTLE_BENCH_MACHINE`
//! set, appends them to `bench/results/helix25.csv`.
#[path = "../../examples/shared/record.rs"]
mod record;

use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::Engine;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .expect("usage: step_windows SCENE [STEPS] [WINDOW]");
    let arg = |k: usize, d: usize| args.get(k).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (steps, window) = (arg(2, 20000), arg(3, 100).max(1));
    let text = std::fs::read_to_string(path).expect("scene file");
    let scene = Scene::parse(&text, path).expect("scene");
    let mut e = Engine::<f64>::new(&scene, usize::MAX).expect("system");
    let ticks0 = cpu_ticks();
    // At least one window, however few the steps.
    let windows = (steps / window).max(1);
    let mut per = Vec::with_capacity(windows);
    for _ in 0..windows {
        let t = Instant::now();
        for _ in 0..window {
            e.step().expect("step");
        }
        per.push(t.elapsed().as_secs_f64() * 1e6 / window as f64);
    }
    let cpu = (cpu_ticks() - ticks0) as f64 * 1e4 / (per.len() * window) as f64;
    per.sort_by(f64::total_cmp);
    let at = |q: f64| per[((per.len() - 1) as f64 * q) as usize];
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in &e.beads.pos {
        for x in v.to_array() {
            h = (h ^ x.to_bits()).wrapping_mul(0x100_0000_01b3);
        }
    }
    let done = per.len() * window;
    let (best, p10, median) = (at(0.0), at(0.1), at(0.5));
    println!(
        "{done} steps: best {best:.3} us, p10 {p10:.3} us, median {median:.3} us a step; CPU {cpu:.2} us a step; positions {h:016x}",
    );
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "helix25",
        format!(
            "cargo run --release -p hydrorattle-host --example step_windows -- {}",
            args[1..].join(" ")
        ),
    );
    let table = format!("best {window}-step window, {done} steps, one thread");
    // The builds of docs/BENCHMARKS.md: the default x86-64 target, and x86-64-v3.
    let case = if cfg!(target_feature = "avx2") {
        "x86-64-v3 (AVX2)"
    } else if cfg!(target_arch = "x86_64") {
        "default (SSE2)"
    } else {
        std::env::consts::ARCH
    };
    for (quantity, value) in [
        ("best window", format!("{best:.3} us")),
        ("p10 window", format!("{p10:.3} us")),
        ("median window", format!("{median:.3} us")),
        ("CPU a step", format!("{cpu:.2} us")),
        ("positions digest", format!("{h:016x}")),
    ] {
        rows.row(&table, case, quantity, &value);
    }
    rows.finish()
        .expect("appending to bench/results/helix25.csv");
}

/// This process's user + system time in clock ticks (100 a second on Linux).
fn cpu_ticks() -> u64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let t = |k: usize| f.get(k).and_then(|s| s.parse::<u64>().ok()).unwrap_or(0);
    // Fields 14 and 15 (utime, stime), counted from the state (field 3) after ')'.
    t(11) + t(12)
}
