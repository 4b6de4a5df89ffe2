//! The Brownian step of the free-space cost model (`host/src/scene/free_cost.rs`): one
//! whole thermal step (`Method::Overdamped`, `kT = 1`, the default midpoint drift and
//! noise square root, no bonds) by each way of giving it its products, over the shapes
//! and counts of `examples/free_cost.rs`, with the Lanczos iterations it took.
//!
//! * dense: the stored mobility, assembled at the start and again at the midpoint; the
//!   noise by its block Cholesky factor up to `LANCZOS_CROSSOVER` spheres, by Lanczos
//!   above (from `REDUCED_MIN` spheres its products read the reduced `f32` copy);
//! * matrix-free: Lanczos on products that evaluate every pair, and the midpoint's
//!   product;
//! * fast (`Params::pse` without a box, tolerance 1e-4): Lanczos on fast products, the
//!   uncorrected draw (free space's RPY mobility is divergence-free), the kernel's
//!   transform kept between steps as a run keeps it.
//!
//! ```text
//! HYDRORATTLE_BENCH_MACHINE=<id> cargo run --release --example free_brownian [-- [MIN_N:]MAX_N [SHAPE...]]
//! ```
//!
//! Counts MIN_N (10) to MAX_N (1e4 by default); the pair paths to 3000 (matrix-free
//! takes some 40 s a step at 1e4, the stored mobility 4.8 GB); past 1e4 the fast path
//! on the cloud at 0.1 alone, at 2e4, 5e4 and 1e5 as MAX_N allows. A path is not timed where its step's
//! storage passes 1 GB, or at the next count once a step took more than 3 s (the pair
//! paths) or 60 s (the fast one). Times are this thread's CPU seconds a step, best of
//! two (past 1e4 the first step alone, its kernel transform included); the same
//! positions and seed every call. With
//! `HYDRORATTLE_BENCH_MACHINE` set the rows go to `bench/results/free_cost.csv`, each
//! path's as soon as it is measured (a stopped run keeps them).

use hydrorattle::integrate::{fast_storage, step_slices};
use hydrorattle::linalg::tri;
use hydrorattle::{Brownian, Layout, Method, NoForce, Noise, Params, Real, State};
use hydrorattle_heap::FreeBuffers;

type V = <f64 as Real>::V3;

#[path = "shared/best.rs"]
mod best;
#[path = "shared/cpu.rs"]
mod cpu;
use best::best;
#[path = "shared/free_shapes.rs"]
#[allow(dead_code)]
mod free_shapes;
#[path = "shared/record.rs"]
mod record;
#[path = "shared/splitmix.rs"]
mod splitmix;
use free_shapes::{SHAPES, chain, cloud};

/// The paths, as the rows name them.
const PATHS: [&str; 3] = ["dense", "matrix-free", "fast 1e-4"];
/// Storage past which a path is not timed (bytes).
const MAX_BYTES: usize = 1_000_000_000;
/// The table the rows go to.
pub const TABLE: &str = "free-space Brownian steps, unit spheres, f64, one thread, CPU seconds a \
                         step (best of two; past 1e4 the first step)";

/// The step's parameters on path `k`.
fn params(k: usize) -> Params<f64> {
    let mut p = Params::<f64>::new(1e-3);
    p.method = Method::Overdamped;
    p.allow_overlap = true;
    p.matrix_free = k > 0;
    p.pse = (k == 2).then_some(1e-4);
    p.brownian = Some(Brownian::new(1.0));
    p
}

/// One step of path `k` from `pos0`, timed (best of `reps`): seconds, Lanczos
/// iterations; `None` where the storage passes `MAX_BYTES`; the step's error as text.
fn time_step(k: usize, pos0: &[V], reps: usize) -> Result<Option<(f64, u32)>, String> {
    let p = params(k);
    let n = pos0.len();
    let rad = vec![1.0; n];
    let density = vec![1.0; n];
    let layout = Layout::for_params(&p, n, 0);
    let size = fast_storage(&p, pos0, &rad).map_err(|e| e.to_string())?;
    let grid = size.map_or(0, FreeBuffers::<f64>::bytes_of);
    // The kernel's workspace: the stored mobility (twice with the midpoint) and the
    // Lanczos basis dominate; a generous bound from the layout's blocks.
    let stored = if k == 0 { 2 * 48 * tri(n) } else { 0 };
    if stored + grid + 8 * 3 * 66 * n > MAX_BYTES {
        return Ok(None);
    }
    let mut arrays = FreeBuffers::<f64>::for_step(size);
    let mut buf = hydrorattle_heap::Buffers::<f64>::new(layout);
    let mut ws = arrays.attach(buf.workspace());
    let (mut pos, mut vel, mut omega) = (pos0.to_vec(), vec![V::ZERO; n], vec![V::ZERO; n]);
    let mut result = Ok(0);
    let mut one = || {
        pos.copy_from_slice(pos0);
        let (mut time, mut rng) = (0.0, Noise::new(11));
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &rad,
            density: &density,
            time: &mut time,
            noise: Some(&mut rng),
        };
        result = step_slices(state, &[], &p, &mut ws, &mut NoForce)
            .map(|r| r.noise_iterations)
            .map_err(|e| e.to_string());
    };
    // The first step computes the fast product's transform; later ones keep it. With
    // `reps` 0 the first step alone is timed (past 1e4, where the transform is a
    // small part of a step of some twenty products).
    let t = if reps == 0 {
        let c = cpu::cpu();
        one();
        c.zip(cpu::cpu()).map_or(f64::NAN, |(a, b)| b - a)
    } else {
        one();
        best(reps, &mut one)
    };
    result.map(|m| Some((t, m)))
}

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let pick = free_shapes::Selection::new(&args);
    let (range, named) = (&pick.range, &pick.named);
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "free_cost",
        format!("cargo run --release --example free_brownian -- {range}{named}"),
    );
    for (shape, phi) in SHAPES {
        if !pick.shape(shape) {
            continue;
        }
        let mut stopped = [false; 3];
        for n in pick.counts() {
            let past = n > 10_000;
            if past && shape != "cloud 0.1" {
                continue;
            }
            let pos = match phi {
                Some(phi) => cloud(n, phi, 11 + n as u64),
                None => chain(n),
            };
            let case = format!("{shape}, N = {n}");
            for (k, path) in PATHS.iter().enumerate() {
                // The pair paths to 3000 spheres: matrix-free at 1e4 takes some 40 s
                // a step, and the stored mobility is past the storage bound.
                if stopped[k] || (n > 3000 && k < 2) {
                    continue;
                }
                let cell = |q: &str| format!("{path} Brownian step{q}");
                match time_step(k, &pos, if past { 0 } else { 2 }) {
                    Ok(Some((t, m))) => {
                        println!("{case}: {path}: {t:.4e} s, {m} Lanczos iterations");
                        rows.row(TABLE, &case, &cell(""), &format!("{t:.4e}"));
                        rows.row(TABLE, &case, &cell(": Lanczos iterations"), &format!("{m}"));
                        stopped[k] = t > if k < 2 { 3.0 } else { 60.0 };
                    }
                    Ok(None) => {
                        println!("{case}: {path}: storage past {MAX_BYTES} bytes");
                        stopped[k] = true;
                    }
                    Err(e) => {
                        println!("{case}: {path}: refused: {e}");
                        rows.row(TABLE, &case, &cell(""), &format!("refused: {e}"));
                    }
                }
                // A step past 1e4 takes minutes: what was measured stays if the run
                // is stopped.
                rows.flush()?;
            }
        }
    }
    rows.finish()
}
