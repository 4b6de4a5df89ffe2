//! Kernel benchmarks (criterion): the stage functions on `Vec`-backed slices, and one
//! `step()` of every method on a settling chain.
//!
//! * `assemble_tt`, `assemble_grand`, `cholesky` (of `mu_tt`), `cholesky_solve` and
//!   `sym_matvec` at N = 8, 25, 100, 256 in f64 and f32;
//! * `step()` per `Method` at N = 8, 16, 25, 64, 128, 256 (and 512 for the overdamped
//!   methods and springs) in f64 and f32;
//! * `scaling/...`: `step_slices` on runtime-sized chains up to N = 2048 (Overdamped
//!   stored and matrix-free, RattleStable), and `solver/...`: dense Newton against
//!   Krylov at N = 16 ... 64 (the `Auto` switch), f64, with iteration counts printed;
//! * `noise_sqrt/{Cholesky,Lanczos}/N`: the thermal overdamped step (kT = 1, midpoint)
//!   with each square root of the mobility at N = 64 ... 1024, Lanczos iterations
//!   printed (the `NoiseSqrt::Auto` crossover);
//! * `brownian/{Deterministic,Lanczos}/N`: the Brownian Overdamped step (kT = 1,
//!   midpoint, Lanczos) and the deterministic one at N = 256 ... 2048 (their
//!   ratio at 1024 and cost exponent), iteration counts printed;
//! * `products/{stored_f64,compact_f32,recompute}/N`: one product `mu_tt x` by each
//!   path at N = 1024, 4096, 8192, one thread, bytes streamed as the throughput;
//! * `contacts/...`: one overdamped step (first and second order) of a folded 25-bead
//!   chain with and without hard contacts, f64, with contact and round counts printed.
//!
//! Particle sets up to N = 512 are built on the stack, so criterion runs on a thread
//! with a large stack; workspaces are on the heap, sized per method.
//!
//! Run: `cargo bench --bench kernel` (add `-- --quick` for a faster pass, or a filter
//! such as `-- step/Rattle`). Results land in `target/criterion/`.

//!
//! One file per group: `stages.rs`, `steps.rs`, `scaling.rs` (also `noise_sqrt`,
//! `brownian` and `solver`), `contacts.rs`, `products.rs`; `shared.rs` holds the chain
//! they share.

mod contacts;
mod products;
mod scaling;
mod shared;
mod stages;
mod steps;

use std::time::Duration;

use criterion::Criterion;

fn run() {
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1500))
        .nresamples(10_000)
        .configure_from_args();
    products::product_paths(&mut c);
    scaling::scaling(&mut c);
    contacts::contact_benches(&mut c);
    stages::stage_benches::<f64>(&mut c, "f64");
    stages::stage_benches::<f32>(&mut c, "f32");
    steps::all_steps::<f64>(&mut c, "f64");
    steps::all_steps::<f32>(&mut c, "f32");
    c.final_summary();
}

fn main() {
    std::thread::Builder::new()
        .name("kernel-bench".into())
        .stack_size(2 << 30)
        .spawn(run)
        .expect("spawn the benchmark thread")
        .join()
        .expect("benchmark thread panicked");
}
