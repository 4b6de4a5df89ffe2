//! One method's steps on the paper's 25-bead chain in f32, for instruction counting:
//! `valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*step_slices*'
//! target/profiling/examples/icount o newton 100` (`cargo build --profile profiling
//! --example icount`: release code with symbols) and divide `Ir` by the step count.
//! Arguments: method (`o`, `o2`, `r`, `s`, `sp`), solver (`newton`, `krylov`, `sweep`,
//! `auto`), steps. Case (c) of Figure 1: head radius 2, tails 1, D = 1.05, dt = 0.01.

use hydrorattle::*;
use hydrorattle_heap::Buffers;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let method = match args.get(1).map(String::as_str).unwrap_or("o") {
        "o2" => Method::Overdamped2,
        "r" => Method::Rattle,
        "s" => Method::RattleStable,
        "sp" => Method::Springs,
        _ => Method::Overdamped,
    };
    let kind = match args.get(2).map(String::as_str).unwrap_or("auto") {
        "newton" => SolverKind::Newton,
        "krylov" => SolverKind::Krylov,
        "sweep" => SolverKind::Sweep,
        _ => SolverKind::Auto,
    };
    let steps: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(100);
    let mut ps: ParticleSet<f32, 25> = ParticleSet::new();
    let mut phi = 0.0f64;
    let mut prev = 2.0;
    for k in 0..25 {
        let a = if k == 0 { 2.0 } else { 1.0 };
        if k > 0 {
            let d: f64 = 1.05 * (a + prev);
            phi += 2.0 * ((d * d - 0.25).sqrt() / 6.0).asin();
        }
        let at = [3.0 * phi.cos(), 3.0 * phi.sin(), 0.5 * k as f64];
        ps.push(Particle::new(f32::v3_from(at), a as f32, 4.5))
            .unwrap();
        prev = a;
    }
    let bonds: BondSet<f32, 24> = BondSet::chain(&ps.pos[..25]).unwrap();
    let mut p = Params::new(0.01f32);
    p.method = method;
    p.solver.kind = kind;
    let mut store = Buffers::<f32>::new(Layout::for_params(&p, 25, 24));
    let mut ws = store.workspace();
    let mut its = 0;
    for _ in 0..steps {
        its += step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap()
            .iterations;
    }
    println!(
        "{method:?} {kind:?}: {:.2} iterations per step",
        its as f64 / steps as f64
    );
}
