//! Overdamped f64 steps of an N-bead settling helix on 1 and on more threads: the time
//! per step, the speedup, and whether the positions' bits agree.
//!
//! `cargo run --release -p hydrorattle-parallel --example speedup -- [N] [STEPS] [THREADS] [MODE]`
//! (defaults 2048, 5, 2, `plain`). MODE `plain`: the deterministic step (the default
//! parameters); `compact`: with [`Params::compact_products`] (the constraint products
//! from the `f32` copy); `free`: [`Params::matrix_free`] (every product recomputes its
//! pairs: compute-bound, the path that scales with cores); `brownian`: the thermal step (kT = 1, midpoint drift, Lanczos
//! noise from the reduced copy; the same noise seed on every run), the Brownian twin;
//! `brownian-compact`: that with [`Params::compact_products`] (its constraint products
//! from the noise's copy too).
//! Each thread count runs the same steps from the same start three times; the best time
//! is kept (the machine may be shared). The constraint products (and Lanczos
//! iterations) of the last step are printed: counts beside the times.

use std::time::Instant;

mod common;

use hydrorattle::glam::DVec3;
use hydrorattle::{Layout, NoForce, Noise, Parallel, Serial, State, StepReport, step_slices};
use hydrorattle_heap::Buffers;
use hydrorattle_parallel::Threads;

fn main() {
    let arg = common::arg;
    let (n, steps, threads) = (arg(1, 2048), arg(2, 5), arg(3, 2));
    let mode = std::env::args().nth(4).unwrap_or_else(|| "plain".into());
    let start = common::helix(n);
    let bonds = common::chain(&start);
    let radius = vec![1.0; n];
    let density = vec![4.5; n];
    let p = common::params(&mode);
    let mut store = Buffers::<f64>::new(Layout::for_params(&p, n, n - 1));
    let run = |par: &dyn Parallel, store: &mut Buffers<f64>| {
        let mut ws = store.workspace().with_parallel(par);
        let mut best = f64::INFINITY;
        let mut pos = start.clone();
        let mut last: Option<StepReport<f64>> = None;
        for _ in 0..3 {
            pos = start.clone();
            let (mut vel, mut omega, mut time) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n], 0.0);
            let mut noise = Noise::new(7);
            let t0 = Instant::now();
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
                last = Some(step_slices(state, &bonds, &p, &mut ws, &mut NoForce).unwrap());
            }
            best = best.min(t0.elapsed().as_secs_f64() / steps as f64);
        }
        (best, pos, last)
    };
    let (one, serial, report) = run(&Serial, &mut store);
    let pool = Threads::new(threads).unwrap();
    let (many, threaded, _) = run(&pool, &mut store);
    let same = serial
        .iter()
        .zip(&threaded)
        .all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits));
    let counts = report.map_or(String::new(), |r| {
        format!(
            ", last step: {} constraint products, {} Lanczos iterations, {} midpoint products",
            r.iterations, r.noise_iterations, r.velocity_iterations
        )
    });
    println!(
        "N = {n} {mode}, {steps} steps: 1 thread {:.2} ms/step, {} threads {:.2} ms/step, \
         speedup {:.2}x, bits {}{counts}",
        one * 1e3,
        pool.threads(),
        many * 1e3,
        one / many,
        if same { "identical" } else { "DIFFERENT" }
    );
}
