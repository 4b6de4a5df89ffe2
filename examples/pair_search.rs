//! The cost of a step's pair searches against the number of spheres: free-draining
//! spheres on a cubic lattice (spacing 3, no contact forms) settling with hard
//! contacts on, matrix-free. The pair searches (the contacts' search twice, the
//! acceptance's check once) are the part that differs between the cell list and every
//! pair (the free-draining product still visits every pair, the same in both). To find
//! where the cell list starts to pay, build it with `cell_list::CELLS_MIN` set to 8
//! (always a cell list) and to `usize::MAX` (never), and compare:
//!
//! ```text
//! cargo run --release --example pair_search
//! ```
//!
//! Prints this thread's CPU time per step (best of 5; loaded machines: read ratios).

use std::time::Instant;

use hydrorattle::{
    Contacts, Hydro, Layout, Method, NoForce, Params, Real, SolverKind, State, step_slices,
};
use hydrorattle_heap::Buffers;

#[path = "shared/cpu.rs"]
mod cpu;
use cpu::cpu;

type V = <f64 as Real>::V3;

/// CPU seconds per step of `n` spheres (best of 5 runs of at least 0.2 s each).
fn per_step(n: usize) -> f64 {
    let side = (n as f64).cbrt().ceil() as usize;
    let start: Vec<V> = (0..n)
        .map(|k| {
            let (x, y, z) = (k % side, (k / side) % side, k / (side * side));
            V::new(x as f64, y as f64, z as f64) * 3.0
        })
        .collect();
    let mut p = Params::<f64>::new(0.05);
    p.method = Method::Overdamped;
    p.hydro = Hydro::FreeDraining;
    p.matrix_free = true;
    p.solver.kind = SolverKind::Krylov;
    p.contacts = Some(Contacts::new(n));
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, 0));
    let mut ws = buf.workspace();
    let (radius, density) = (vec![1.0; n], vec![4.5; n]);
    (0..5)
        .map(|_| {
            let mut pos = start.clone();
            let (mut vel, mut omega, mut time) = (vec![V::ZERO; n], vec![V::ZERO; n], 0.0);
            let (t, c) = (Instant::now(), cpu());
            let mut steps = 0;
            loop {
                let state = State {
                    pos: &mut pos,
                    vel: &mut vel,
                    omega: &mut omega,
                    radius: &radius,
                    density: &density,
                    time: &mut time,
                    noise: None,
                };
                step_slices(state, &[], &p, &mut ws, &mut NoForce).expect("step");
                steps += 1;
                let used = match (c, cpu()) {
                    (Some(a), Some(b)) => b - a,
                    _ => t.elapsed().as_secs_f64(),
                };
                if used >= 0.2 {
                    return used / steps as f64;
                }
            }
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    println!(
        "cell list from {} spheres",
        hydrorattle::cell_list::CELLS_MIN
    );
    for n in [16, 32, 48, 64, 96, 128, 192, 256, 512, 1024, 4096] {
        println!("N = {n:5}: {:.2} us per step", per_step(n) * 1e6);
    }
}
