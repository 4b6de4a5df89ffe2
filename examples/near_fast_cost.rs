//! Cost of one `Overdamped` step with the iterative near field on its two far fields,
//! against plain RPY steps: a random suspension of `N` spheres (radii 0.8 to 1.2, volume
//! fraction 0.25 in a cube), f64, one thread, this thread's CPU time (a loaded machine's
//! waits do not count). In free space (the cube no box) the paths are:
//!
//! * `fast RPY`: the fast free-space product alone (`Params::pse`, no near field);
//! * `near, fast far field`: the iterative near field (`Params::near` with
//!   `Params::matrix_free`) on the fast product's grand product, no `tri(2N)` storage;
//! * `near, assembled far field`: the same on the grand mobility assembled once
//!   (`tri(2N)` blocks of 72 bytes: 2.3 GB at 4000; skipped with `fast`).
//!
//! With `box` the cube is the periodic box and the paths are PSE's and the Ewald sums':
//! `PSE RPY` (PSE's product alone), `near, PSE far field` (on PSE's grand product),
//! `near, Ewald far field` (on the Ewald grand mobility assembled; skipped with `fast`)
//! and `Ewald RPY` (the plain step on the Ewald sums' assembled `mu_tt`, as
//! `near_box_cost` times it; skipped with `fast`), each step also over the last's.
//!
//! ```text
//! cargo run --release --example near_fast_cost                   # N = 1000 4000, tolerance 1e-4
//! cargo run --release --example near_fast_cost -- 1e-4 1000 fast # without the assembled path
//! cargo run --release --example near_fast_cost -- 1e-4 1000 box  # in the box
//! ```
//!
//! Prints one row per `N` and path: the step's CPU seconds, the close pairs, the near
//! field's products and conjugate-gradient iterations, the far field's products
//! (iterations plus two a product), the storage (the workspace's layout and the fast
//! product's arrays), and the largest velocity difference from the assembled path's over
//! its largest velocity. Where `HYDRORATTLE_BENCH_MACHINE` names the machine, appends
//! records to `bench/results/near_fast_cost.csv` (in the box `near_pse_cost.csv`).

#[path = "shared/cpu.rs"]
mod cpu;
#[path = "shared/record.rs"]
mod record;
#[path = "shared/suspension.rs"]
mod suspension;

use hydrorattle::integrate::{fast_storage, fast_vectors, pse_storage, step_slices};
use hydrorattle::stokesian::NearField;
use hydrorattle::{Layout, Method, NoForce, Params, Periodic, Real, State, StepReport};
use hydrorattle_heap::{Buffers, FreeBuffers, PseBuffers};

type V = <f64 as Real>::V3;

/// Density of unit buoyant weight for a unit sphere (`g = 1`).
const RHO1: f64 = 3.0 / (4.0 * std::f64::consts::PI);

/// The paths: name, near field, fast product; the assembled near path third.
const PATHS: [(&str, bool, bool); 3] = [
    ("fast RPY", false, true),
    ("near, fast far field", true, true),
    ("near, assembled far field", true, false),
];

/// The box's paths (`box`), as [`PATHS`]; the plain Ewald step last.
const BOX_PATHS: [(&str, bool, bool); 4] = [
    ("PSE RPY", false, true),
    ("near, PSE far field", true, true),
    ("near, Ewald far field", true, false),
    ("Ewald RPY", false, false),
];

/// A step's report and the velocities after it.
type Stepped = (StepReport<f64>, Vec<V>);

/// One step of `p` from `pos0`: CPU seconds, the report and the velocities (or the
/// step's error), the storage in bytes.
fn one(p: &Params<f64>, pos0: &[V], rad: &[f64]) -> (f64, Result<Stepped, String>, usize) {
    let n = pos0.len();
    let density = vec![RHO1; n];
    let layout = Layout::for_params(p, n, 0);
    let size = fast_storage(p, pos0, rad).unwrap();
    let mut arrays = FreeBuffers::<f64>::for_step(size);
    // PSE's arrays in the box (empty in free space).
    let mut pse = PseBuffers::<f64>::for_step(pse_storage(p, rad).unwrap());
    let pse_bytes = pse.complex.len() * std::mem::size_of::<[f64; 2]>()
        + pse.index.len() * std::mem::size_of::<usize>()
        + pse.vectors.len() * std::mem::size_of::<V>();
    let bytes = layout.bytes::<f64>() + arrays.bytes() + pse_bytes;
    let mut buf = Buffers::<f64>::new(layout);
    let mut spare = vec![V::ZERO; fast_vectors(p, n)];
    // (The fast vectors take the vectors' slot PSE's arrays hold.)
    let mut ws = match p.periodic {
        Some(_) => pse.attach(buf.workspace()),
        None => arrays.attach(buf.workspace()).with_fast_vectors(&mut spare),
    };
    let (mut pos, mut vel, mut omega) = (pos0.to_vec(), vec![V::ZERO; n], vec![V::ZERO; n]);
    let mut time = 0.0;
    let state = State {
        pos: &mut pos,
        vel: &mut vel,
        omega: &mut omega,
        radius: rad,
        density: &density,
        time: &mut time,
        noise: None,
    };
    let c0 = cpu::cpu().expect("CPU time (Linux)");
    let r = step_slices(state, &[], p, &mut ws, &mut NoForce);
    let t = cpu::cpu().expect("CPU time") - c0;
    (t, r.map(|r| (r, vel)).map_err(|e| e.to_string()), bytes)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let tol: f64 = args.first().map_or(1e-4, |s| s.parse().expect("tolerance"));
    let mut ns: Vec<usize> = args.iter().skip(1).filter_map(|a| a.parse().ok()).collect();
    let skip_assembled = args.iter().any(|a| a == "fast");
    let boxed = args.iter().any(|a| a == "box");
    if ns.is_empty() {
        ns = vec![1000, 4000];
    }
    let paths: &[(&str, bool, bool)] = if boxed { &BOX_PATHS } else { &PATHS };
    let mut rec = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        if boxed {
            "near_pse_cost"
        } else {
            "near_fast_cost"
        },
        format!(
            "cargo run --release --example near_fast_cost -- {}",
            args.join(" ")
        ),
    );
    let table = match boxed {
        true => format!(
            "one Overdamped step with the iterative near field on PSE's far field in the periodic box, suspension at volume fraction 0.25, f64, one thread, CPU time, tolerance {tol:e}"
        ),
        false => format!(
            "one Overdamped step with the iterative near field on the fast far field, free-space suspension at volume fraction 0.25, f64, one thread, CPU time, tolerance {tol:e}"
        ),
    };
    println!(
        "N,path,step CPU s,close pairs,near products,CG iterations,far products,storage MB,velocity vs assembled,over the last path"
    );
    for &n in &ns {
        let (pos, rad, l) = suspension::suspension(n, 0.25);
        let pos: Vec<V> = pos.iter().map(|p| f64::v3_from(p.to_array())).collect();
        let mut rows = vec![];
        for &(path, near, fast) in paths {
            if skip_assembled && !fast {
                continue;
            }
            let mut p = Params::<f64>::new(1e-4);
            p.method = Method::Overdamped;
            p.periodic = boxed.then(|| Periodic::new([l; 3]).expect("box"));
            // The plain Ewald step assembles `mu_tt`; every other path is matrix-free.
            p.matrix_free = near || fast;
            p.near = near.then(NearField::default);
            p.pse = fast.then_some(tol);
            let (t, r, bytes) = one(&p, &pos, &rad);
            match r {
                Ok((r, vel)) => rows.push((path, t, r, vel, bytes)),
                Err(e) => println!("{n},{path},{t:.3},refused: {e}"),
            }
        }
        let assembled = rows.iter().find(|r| r.0 == paths[2].0).map(|r| r.3.clone());
        let last = rows.iter().find(|r| r.0 == paths[paths.len() - 1].0);
        let last = last.map(|r| r.1);
        for (path, t, r, vel, bytes) in &rows {
            let far = r.near_iterations + 2 * r.near_products;
            let diff = match (&assembled, r.near_products > 0) {
                (Some(a), true) => {
                    let big = a.iter().map(|v| f64::norm2(*v).sqrt()).fold(0.0, f64::max);
                    let d = vel.iter().zip(a).map(|(x, y)| f64::norm2(*x - *y).sqrt());
                    format!("{:.2e}", d.fold(0.0, f64::max) / big)
                }
                _ => "-".into(),
            };
            let mb = *bytes as f64 / 1e6;
            let ratio = last.map_or("-".into(), |e| format!("{:.2}", t / e));
            println!(
                "{n},{path},{t:.3},{},{},{},{far},{mb:.1},{diff},{ratio}",
                r.near_pairs, r.near_products, r.near_iterations
            );
            let case = format!("N = {n}, {path}");
            let cells = [
                ("step, CPU s", format!("{t:.3e}")),
                ("close pairs", r.near_pairs.to_string()),
                ("near-field products", r.near_products.to_string()),
                (
                    "conjugate-gradient iterations",
                    r.near_iterations.to_string(),
                ),
                ("far-field products", far.to_string()),
                ("storage, MB", format!("{mb:.1}")),
                ("velocity vs assembled far field", diff),
            ];
            // In the box, each step over the plain Ewald step (the issue's measure).
            let ratio = ("step over the Ewald RPY step", ratio);
            let cells = cells.into_iter().chain(boxed.then_some(ratio));
            for (quantity, value) in cells {
                rec.row(&table, &case, quantity, &value);
            }
        }
    }
    if let Err(e) = rec.finish() {
        eprintln!("recording failed: {e}");
    }
}
