//! Cost of one step of a sedimenting cloud on the fast free-space product
//! (`Params::pse` without a box), against the matrix-free pair blocks and the dense
//! stored mobility. Unit spheres uniformly in a ball at volume fraction 0.05 (overlaps
//! allowed: equal radii never nest), densities 1 to 3, `Method::Overdamped`, f64, one
//! thread; a deterministic step, then a Brownian one (`kT = 1`, Lanczos noise).
//!
//! ```text
//! cargo run --release --example fast_step                 # N = 1e4, tolerance 1e-4, all three
//! cargo run --release --example fast_step -- 1e-4 3000 10000 fast,free
//! ```
//!
//! Arguments: the tolerance, the N, and the paths among `fast`, `free` (matrix-free
//! pair blocks) and `dense` (the stored mobility, `tri(N)` blocks of 48 bytes: 2.4 GB at
//! 1e4). Prints one row per N and path: this thread's CPU seconds for the step, the
//! largest displacement difference against the first path's over its largest
//! displacement, and the fast path's storage.

use hydrorattle::integrate::{fast_storage, step_slices};
use hydrorattle::{Brownian, Layout, Method, NoForce, Noise, Params, Real, State};
use hydrorattle_heap::FreeBuffers;

type V = <f64 as Real>::V3;

#[path = "shared/cpu.rs"]
mod cpu;
#[path = "shared/splitmix.rs"]
mod splitmix;
use splitmix::Rng;

/// `n` unit spheres uniformly in a ball at volume fraction `phi`.
fn cloud(n: usize, phi: f64, seed: u64) -> Vec<V> {
    let radius = (n as f64 / phi).cbrt();
    let mut rng = Rng(seed);
    let mut pos = Vec::with_capacity(n);
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| radius * (2.0 * rng.unit() - 1.0));
        if p.iter().map(|x| x * x).sum::<f64>() <= radius * radius {
            pos.push(f64::v3_from(p));
        }
    }
    pos
}

/// One step of `p` from `pos0` (the generator `seed` where thermal): CPU seconds, the
/// positions after (or the step's error), the fast storage in bytes.
fn one(p: &Params<f64>, pos0: &[V], seed: u64) -> (f64, Result<Vec<V>, String>, usize) {
    let n = pos0.len();
    let rad = vec![1.0; n];
    let density: Vec<f64> = (0..n).map(|i| 1.0 + (i % 3) as f64).collect();
    let size = fast_storage(p, pos0, &rad).unwrap();
    let mut arrays = FreeBuffers::<f64>::for_step(size);
    let bytes = arrays.bytes();
    let mut buf = hydrorattle_heap::Buffers::<f64>::new(Layout::for_params(p, n, 0));
    let mut ws = arrays.attach(buf.workspace());
    let (mut pos, mut vel, mut omega) = (pos0.to_vec(), vec![V::ZERO; n], vec![V::ZERO; n]);
    let (mut time, mut rng) = (0.0, Noise::new(seed));
    let state = State {
        pos: &mut pos,
        vel: &mut vel,
        omega: &mut omega,
        radius: &rad,
        density: &density,
        time: &mut time,
        noise: p.brownian.map(|_| &mut rng),
    };
    let c0 = cpu::cpu();
    let t0 = std::time::Instant::now();
    let r = step_slices(state, &[], p, &mut ws, &mut NoForce);
    let t = match (c0, cpu::cpu()) {
        (Some(a), Some(b)) => b - a,
        _ => t0.elapsed().as_secs_f64(),
    };
    (t, r.map(|_| pos).map_err(|e| e.to_string()), bytes)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let tol: f64 = args.first().map_or(1e-4, |s| s.parse().unwrap());
    let mut ns: Vec<usize> = vec![];
    let mut paths = vec!["fast", "free", "dense"];
    for a in args.iter().skip(1) {
        match a.parse::<f64>() {
            Ok(x) => ns.push(x as usize),
            Err(_) => paths = a.split(',').collect(),
        }
    }
    if ns.is_empty() {
        ns.push(10_000);
    }
    println!("N,thermal,path,step CPU s,vs first path,fast storage MB");
    for &n in &ns {
        let pos0 = cloud(n, 0.05, 7);
        for thermal in [false, true] {
            let mut first: Option<Vec<V>> = None;
            for &path in &paths {
                let mut p = Params::<f64>::new(0.01);
                p.method = Method::Overdamped;
                p.allow_overlap = true;
                p.matrix_free = path != "dense";
                p.pse = (path == "fast").then_some(tol);
                if thermal {
                    p.brownian = Some(Brownian::new(1.0));
                }
                let (t, pos, bytes) = one(&p, &pos0, 11);
                let pos = match pos {
                    Ok(pos) => pos,
                    Err(e) => {
                        println!("{n},{thermal},{path},{t:.3},refused: {e},");
                        continue;
                    }
                };
                let disp = pos
                    .iter()
                    .zip(&pos0)
                    .map(|(a, b)| f64::norm2(*a - *b).sqrt())
                    .fold(0.0, f64::max);
                // Thermal steps draw differently on each path (free space's matrix-free
                // step keeps the midpoint; the fast one, like PSE's, does not).
                let diff = match (&first, thermal) {
                    (Some(f), false) => {
                        let d = pos.iter().zip(f).map(|(a, b)| f64::norm2(*a - *b).sqrt());
                        format!("{:.2e}", d.fold(0.0, f64::max) / disp)
                    }
                    _ => "-".into(),
                };
                first.get_or_insert(pos);
                let mb = bytes as f64 / 1e6;
                println!("{n},{thermal},{path},{t:.3},{diff},{mb:.1}");
            }
        }
    }
}
