//! The fast free-space product (`mobility::free_fast`, f64) of N unit spheres uniformly
//! in a ball at volume fraction 0.05 on one thread and on more: the wall time of one
//! product (kernel kept, best of a few), the time each phase's round took on its busiest
//! thread, and whether the bits agree.
//!
//! ```text
//! cargo run --release -p hydrorattle-parallel --example free_fast_threads -- [TOL] [THREADS] [N...]
//! ```
//! (defaults 1e-4, 2, N = 1e4 and 1e5). Phases: the near part (pairs, then the partial
//! sums), spreading, the `x` and `y` transforms forward, the `z` lines with the kernel
//! (in rounds), the `y` and `x` transforms back, interpolation; "serial" is the rest (the
//! checks, the cell list, the rows put in place). With `HYDRORATTLE_BENCH_MACHINE` set,
//! the rows go to `bench/results/free_fast_threads.csv`. With `GRAND=1`, the grand
//! product (`new_grand`'s parameters, torques as well as forces). The product's
//! relative error at the first 1000 spheres against the direct RPY sum is printed and
//! recorded. With `STEP=1`, steps
//! of the cloud sedimenting instead (`common/fast_steps.rs`): the first on zeroed arrays
//! (the kernel's transform computed), the second with it kept, and the second again on
//! zeroed arrays (the same bits), wall and CPU seconds on 1 and `THREADS` threads.

mod common;
#[path = "common/fast_steps.rs"]
mod fast_steps;
#[path = "../../examples/shared/record.rs"]
mod record;
#[path = "../../examples/shared/splitmix.rs"]
mod splitmix;

use std::sync::Mutex;
use std::time::Instant;

use common::timed::{Round, Timed};
use hydrorattle::glam::DVec3;
use hydrorattle::mobility::free_fast::{FreeFast, FreeStorage};
use hydrorattle::mobility::{Hydro, tt_block_at};
use hydrorattle::{Parallel, Serial};
use hydrorattle_heap::FreeBuffers;
use hydrorattle_parallel::Threads;
use splitmix::Rng;

/// `n` unit spheres uniformly in a ball at volume fraction `phi`, and forces in
/// `[-1, 1]^3` (the scaling example's cloud).
fn cloud(n: usize, phi: f64, seed: u64) -> (Vec<DVec3>, Vec<DVec3>, f64) {
    let radius = (n as f64 / phi).cbrt();
    let mut rng = Rng(seed);
    let mut pos = Vec::with_capacity(n);
    while pos.len() < n {
        let p = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * (2.0 * radius) - radius;
        if p.length_squared() <= radius * radius {
            pos.push(p);
        }
    }
    let mut v = || 2.0 * rng.unit() - 1.0;
    let f = (0..n).map(|_| DVec3::new(v(), v(), v())).collect();
    (pos, f, radius)
}

const PHASES: [&str; 8] = [
    "near pairs",
    "near partial sums",
    "spreading",
    "x, y forward",
    "z lines and kernel",
    "y, x back",
    "interpolation",
    "serial",
];

/// The phases' seconds on their busiest threads, from one product's rounds.
fn phases(log: &[Round], wall: f64) -> [f64; 8] {
    let s = |r: &Round| r.busiest as f64 * 1e-9;
    let k = log.len();
    let mut p = [0.0; 8];
    if k < 7 {
        return p;
    }
    for (q, r) in [0, 1, 2, 3].into_iter().zip(&log[..4]) {
        p[q] = s(r);
    }
    p[4] = log[4..k - 2].iter().map(s).sum();
    p[5] = s(&log[k - 2]);
    p[6] = s(&log[k - 1]);
    p[7] = (wall - log.iter().map(|r| r.wall as f64 * 1e-9).sum::<f64>()).max(0.0);
    p
}

/// Spheres whose velocities [`error`] checks.
const ROWS: usize = 1000;

/// The relative error of `u` at the first [`ROWS`] spheres against the direct RPY sum
/// (the kernel's pair blocks, `mobility::tt_block_at`, viscosity 1).
fn error(pos: &[DVec3], rad: &[f64], f: &[DVec3], u: &[DVec3]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (i, ui) in u.iter().enumerate().take(ROWS) {
        let mut v = DVec3::ZERO;
        for (j, fj) in f.iter().enumerate() {
            let b = tt_block_at(Hydro::Rpy, 1.0, pos, rad, i, j).expect("never nested");
            v += b * *fj;
        }
        num += (*ui - v).length_squared();
        den += v.length_squared();
    }
    (num / den).sqrt()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let tol: f64 = args.first().map_or(1e-4, |s| s.parse().unwrap());
    let threads: usize = args.get(1).map_or(2, |s| s.parse().unwrap());
    let ns: Vec<usize> = match args.len() {
        0..=2 => vec![10_000, 100_000],
        _ => args[2..]
            .iter()
            .map(|s| s.parse::<f64>().unwrap() as usize)
            .collect(),
    };
    let step_mode = std::env::var("STEP").is_ok_and(|g| g == "1");
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "free_fast_threads",
        format!(
            "{}cargo run --release -p hydrorattle-parallel --example free_fast_threads -- {}",
            if step_mode { "STEP=1 " } else { "" },
            args.join(" ")
        ),
    );
    let grand = std::env::var("GRAND").is_ok_and(|g| g == "1");
    let what = if grand { "grand product" } else { "product" };
    let table = format!(
        "fast free-space RPY {what} on threads, unit spheres in a ball at volume fraction 0.05, f64, tolerance {tol:e}, wall seconds (best of 3)"
    );
    let step_table = format!(
        "a sedimenting cloud's Overdamped step on the fast free-space product, unit spheres in a ball at volume fraction 0.05, densities 1 to 3, dt 0.01, f64, tolerance {tol:e}, one run"
    );
    for &n in &ns {
        let (pos, f, radius) = cloud(n, 0.05, 7 + n as u64);
        if step_mode {
            println!("N {n}, steps:");
            let case = format!("N = {n}");
            fast_steps::steps(tol, threads, &pos, |q, v| {
                rows.row(&step_table, &case, q, v)
            });
            continue;
        }
        let rad = vec![1.0; n];
        let ff = match grand {
            true => FreeFast::<f64>::new_grand(1.0, tol, [2.0 * radius; 3], n),
            false => FreeFast::<f64>::new(1.0, tol, [2.0 * radius; 3], n),
        }
        .unwrap();
        let size = ff.storage_grand(n);
        let torque: Vec<DVec3> = f.iter().rev().copied().collect();
        let mut arrays = FreeBuffers::new(size);
        let pool = Threads::new(threads).unwrap();
        let mut results: Vec<(usize, f64, [f64; 8], Vec<DVec3>)> = Vec::new();
        for (t, inner) in [
            (1, &Serial as &dyn Parallel),
            (threads, &pool as &dyn Parallel),
        ] {
            let timed = Timed {
                inner,
                log: Mutex::new(Vec::new()),
            };
            let mut store = arrays.storage().with_parallel(&timed);
            let (mut out, mut spin) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
            let mut product = |out: &mut [DVec3], store: &mut FreeStorage<'_, f64>| match grand {
                true => ff.apply_grand(1.0, (&pos, &rad), &f, &torque, out, &mut spin, store),
                false => ff.apply(1.0, &pos, &rad, &f, out, store),
            };
            // The first product computes the kernel's transform.
            product(&mut out, &mut store).unwrap();
            let (mut best, mut split) = (f64::INFINITY, [0.0; 8]);
            for _ in 0..3 {
                timed.log.lock().unwrap().clear();
                let t0 = Instant::now();
                product(&mut out, &mut store).unwrap();
                let wall = t0.elapsed().as_secs_f64();
                if wall < best {
                    best = wall;
                    split = phases(&timed.log.lock().unwrap(), wall);
                }
            }
            results.push((t, best, split, out));
        }
        let same = results[0].3 == results[1].3;
        if !grand {
            let err = error(&pos, &rad, &f, &results[1].3);
            println!(
                "N {n}: error {err:.2e} against the direct RPY sum at the first {ROWS} spheres"
            );
            let q =
                format!("relative error against the direct RPY sum at the first {ROWS} spheres");
            rows.row(&table, &format!("N = {n}"), &q, &format!("{err:.2e}"));
        }
        let case = match grand {
            true => format!("N = {n}, grand product"),
            false => format!("N = {n}"),
        };
        for (t, best, split, _) in &results {
            let parts: Vec<String> = PHASES
                .iter()
                .zip(split)
                .map(|(p, s)| format!("{p} {s:.3}"))
                .collect();
            println!(
                "N {n}, grid {:?}, {t} thread(s): {best:.3} s ({})",
                ff.grid(),
                parts.join(", ")
            );
            let busy: f64 = split.iter().sum();
            println!("  sum of the phases: {busy:.3} s");
            rows.row(
                &table,
                &case,
                &format!("seconds, one product, {t} thread(s)"),
                &format!("{best:.3}"),
            );
            let q = format!("seconds, sum of the phases, {t} thread(s)");
            rows.row(&table, &case, &q, &format!("{busy:.3}"));
            for (p, s) in PHASES.iter().zip(split) {
                let q = format!("seconds, {p} (busiest thread), {t} thread(s)");
                rows.row(&table, &case, &q, &format!("{s:.3}"));
            }
        }
        let speedup = results[0].1 / results[1].1;
        println!("N {n}: speedup {speedup:.2} on {threads} threads, same bits: {same}");
        rows.row(
            &table,
            &case,
            &format!("speedup on {threads} threads"),
            &format!("{speedup:.2}"),
        );
        rows.row(
            &table,
            &case,
            "same bits on 1 and more threads",
            &same.to_string(),
        );
    }
    rows.finish().unwrap();
}
