//! Time per step against the particle count, for exploring the solvers at scale.
//!
//! `cargo run --release --example scale -- METHOD SOLVER N [N ...]` with METHOD one of
//! `o`, `o2`, `r`, `s`, `sp` and SOLVER `auto`, `newton`, `krylov`, `sweep`. A helical
//! chain (radius 3, rise 0.5 per bead, tails of radius 1, head 2^(1/3), bonds 1.05 (a_i +
//! a_j)) settles under gravity with dt = 0.01 for `STEPS` steps (default 5). Prints
//! milliseconds per step and constraint iterations (PCG iterations for Krylov).
//! `MF=1` runs matrix-free (Overdamped, Springs), `DT=x` sets the time step. `KT=x` adds
//! thermal noise at `kT = x` (Overdamped, Springs; midpoint drift, `UNCORRECTED=1` for
//! the other) by Lanczos (`LTOL=x` its tolerance), and prints its iterations too. For
//! instruction counts: `valgrind --tool=callgrind --collect-atstart=no
//! --toggle-collect='*step_slices*' target/profiling/examples/scale o auto 1024` (built
//! with `--profile profiling`: release code with symbols).
//! `CHAIN=1` takes the kernel bench's chain (`benches/kernel/shared.rs`, `brownian/...`)
//! instead of the helix. `BOX=L` runs in a cubic periodic box of edge `L` (the Ewald
//! mobility, `docs/PERIODIC.md`). `COMPACT=1` sets `Params::compact_products` (the
//! Krylov constraint products from the compact `f32` copy, where the kernel takes it:
//! Overdamped, N >= 700, free space or a box). Each line ends with a digest of the final positions'
//! bits (the same on every build that keeps the arithmetic). With
//! `HYDRORATTLE_BENCH_MACHINE` set, appends each line's numbers to
//! `bench/results/large-n.csv`.
#[path = "shared/record.rs"]
mod record;

use hydrorattle::*;
use hydrorattle_heap::Buffers;

fn helix(n: usize) -> (Vec<glam::DVec3>, Vec<f64>) {
    let mut pos = Vec::with_capacity(n);
    let mut rad = Vec::with_capacity(n);
    for k in 0..n {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        // Arc length per bead ~ 2.1 around a circle of radius 3, rising 0.8 per bead.
        let ph = k as f64 * 0.68;
        pos.push(glam::DVec3::new(
            3.0 * ph.cos(),
            3.0 * ph.sin(),
            0.8 * k as f64,
        ));
        rad.push(a);
    }
    (pos, rad)
}

/// The chain of `benches/kernel/shared.rs` (`chain_geometry`): turning 0.6 rad per bead,
/// rising 0.8, bonds 1.5 (a_i + a_j).
fn chain(n: usize) -> (Vec<glam::DVec3>, Vec<f64>) {
    let (mut pos, mut rad) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut at, mut prev) = (glam::DVec3::ZERO, 0.0);
    for k in 0..n {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        if k > 0 {
            let t = 0.6 * k as f64;
            at += glam::DVec3::new(t.cos(), t.sin(), 0.8).normalize() * 1.5 * (a + prev);
        }
        pos.push(at);
        rad.push(a);
        prev = a;
    }
    (pos, rad)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let method = match args.get(1).map(String::as_str).unwrap_or("o") {
        "o" => Method::Overdamped,
        "o2" => Method::Overdamped2,
        "r" => Method::Rattle,
        "s" => Method::RattleStable,
        _ => Method::Springs,
    };
    let kind = match args.get(2).map(String::as_str).unwrap_or("auto") {
        "newton" => SolverKind::Newton,
        "krylov" => SolverKind::Krylov,
        "sweep" => SolverKind::Sweep,
        _ => SolverKind::Auto,
    };
    let steps: usize = std::env::var("STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    // The command with the variables that changed the run, so that a row reruns.
    let vars = [
        "STEPS",
        "MF",
        "DT",
        "KT",
        "UNCORRECTED",
        "LTOL",
        "CHAIN",
        "BOX",
        "COMPACT",
    ];
    let set: Vec<String> = vars
        .iter()
        .filter_map(|v| std::env::var(v).ok().map(|x| format!("{v}={x} ")))
        .collect();
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "large-n",
        format!(
            "{}cargo run --release --example scale -- {}",
            set.concat(),
            args[1..].join(" ")
        ),
    );
    let table = format!(
        "{method:?} step, solver {kind:?}, {}, f64, mean of {steps} steps",
        if std::env::var("CHAIN").is_ok() {
            "kernel bench's chain"
        } else {
            "helix"
        },
    );
    for n in args[3..].iter().map(|s| s.parse::<usize>().unwrap()) {
        let (mut pos, radius) = match std::env::var("CHAIN").is_ok() {
            true => chain(n),
            false => helix(n),
        };
        let bonds: Vec<Bond<f64>> = (1..n)
            .map(|i| Bond {
                i: i - 1,
                j: i,
                length: (pos[i] - pos[i - 1]).length(),
            })
            .collect();
        let density = vec![4.5; n];
        let (mut vel, mut omega, mut time) =
            (vec![glam::DVec3::ZERO; n], vec![glam::DVec3::ZERO; n], 0.0);
        let dt = std::env::var("DT")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0.01);
        let mut p = Params::new(dt);
        p.method = method;
        p.solver.kind = kind;
        p.allow_overlap = true;
        p.matrix_free = std::env::var("MF").is_ok();
        p.compact_products = std::env::var("COMPACT").is_ok();
        let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<f64>().ok());
        if let Some(l) = env("BOX") {
            p.periodic = Some(Periodic::new([l; 3]).unwrap());
        }
        if let Some(kt) = env("KT") {
            p.brownian = Some(Brownian {
                temperature: kt,
                drift: if std::env::var("UNCORRECTED").is_ok() {
                    Drift::Uncorrected
                } else {
                    Drift::Midpoint
                },
            });
            p.noise_sqrt = NoiseSqrt::Lanczos;
            if let Some(t) = env("LTOL") {
                p.lanczos.tolerance = t;
            }
        }
        let mut noise = Noise::new(1);
        let layout = Layout::for_params(&p, n, bonds.len());
        let mut store = Buffers::<f64>::new(layout);
        let mut ws = store.workspace();
        let t0 = std::time::Instant::now();
        let (mut its, mut lanczos, mut mid) = (0, 0, 0);
        for _ in 0..steps {
            let state = State {
                pos: &mut pos,
                vel: &mut vel,
                omega: &mut omega,
                radius: &radius,
                density: &density,
                time: &mut time,
                noise: p.brownian.map(|_| &mut noise),
            };
            let r = step_slices(state, &bonds, &p, &mut ws, &mut NoForce).unwrap();
            its += r.iterations;
            lanczos += r.noise_iterations;
            mid += r.velocity_iterations;
        }
        let us = t0.elapsed().as_secs_f64() * 1e6 / steps as f64;
        let digest = pos
            .iter()
            .flat_map(|v| v.to_array())
            .fold(0u64, |h, c| (h ^ c.to_bits()).wrapping_mul(0x100_0000_01b3));
        println!(
            "n {n:5}  {us:9.2} us/step  iterations {:6.1}  Lanczos {:5.1}  midpoint {:5.1}  storage {:.1} MB  digest {digest:016x}",
            its as f64 / steps as f64,
            lanczos as f64 / steps as f64,
            mid as f64 / steps as f64,
            layout.bytes::<f64>() as f64 / 1e6
        );
        let case = format!("N = {n}");
        let mean = |x: u32| format!("{:.1}", f64::from(x) / steps as f64);
        for (quantity, value) in [
            ("time a step", format!("{us:.2} us")),
            ("constraint iterations", mean(its)),
            ("Lanczos iterations", mean(lanczos)),
            ("midpoint iterations", mean(mid)),
            (
                "storage",
                format!("{:.1} MB", layout.bytes::<f64>() as f64 / 1e6),
            ),
            ("positions digest", format!("{digest:016x}")),
        ] {
            rows.row(&table, &case, quantity, &value);
        }
    }
    rows.finish()
        .expect("appending to bench/results/large-n.csv");
}
