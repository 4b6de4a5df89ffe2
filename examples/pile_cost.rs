//! The cost of a step of a settling contact pile with the dense Newton solve, at the
//! sizes asked (default 100 and 300 unit spheres) dropped in a column into a fence of bonded heavy
//! spheres on the wall (the geometry of `host/scenes/pile.toml`, dt 0.2, tolerance
//! 1e-10). Each pile runs `STEPS` steps from the drop; the window of the last `WINDOW`
//! steps (the pile landed, contacts and wall links forming and releasing) is timed.
//! Prints, per size, the CPU time a step, the Jacobian factorisations a step
//! (`StepReport::factorizations`), the Newton iterations and active-set rounds a step
//! and the constraint rows held. Then `KRYLOV_STEPS` Krylov steps from each pile's state
//! at the end (the same parameters, `max_iterations` 500: at most 5 000 products a
//! solve) give the products the Krylov constraint solve takes there (the first step's,
//! and the mean a step), or where it gave up, and their CPU time a step. Records them in
//! `bench/results/pile_cost.csv` where `HYDRORATTLE_BENCH_MACHINE` names the machine.
//!
//! ```text
//! cargo run --release --example pile_cost [STEPS WINDOW [COUNT...]]
//! ```
//!
//! A pile of `COUNT` spheres is a column `side` wide (`side^2` a layer, the smallest
//! `side >= 3` with `12 side^2 >= COUNT`) in a fence of `5 side` spheres: 100 spheres
//! in 15, 300 in 25, as `host/scenes/pile.toml`. The last line prints, for each size, the
//! ratio of Krylov's CPU time a step to Newton's: where it falls below 1 is where
//! `SolverKind::Auto` should stop choosing Newton for contact piles.

use std::time::Instant;

use hydrorattle::{
    Bond, Contacts, Layout, Method, NoForce, Params, Real, SolverKind, State, StepError, Wall,
    step_slices,
};
use hydrorattle_heap::Buffers;

#[path = "shared/cpu.rs"]
mod cpu;
#[path = "shared/record.rs"]
mod record;
use cpu::cpu;

type V = <f64 as Real>::V3;

/// A fence of `fence` spheres of radius 1.5 (density 10) 0.002 apart, bonded in a ring,
/// and `count` unit spheres (density 4.5) in a column `side` wide, 2.3 apart, each
/// centre jittered by a fixed pattern.
fn pile(fence: usize, side: usize, count: usize) -> (Vec<V>, Vec<f64>, Vec<f64>, Vec<Bond<f64>>) {
    let ring = 1.501 / (std::f64::consts::PI / fence as f64).sin();
    let (mut pos, mut radius, mut density) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..fence {
        let a = std::f64::consts::TAU * i as f64 / fence as f64;
        pos.push(V::new(ring * a.cos(), ring * a.sin(), 1.5));
        radius.push(1.5);
        density.push(10.0);
    }
    let jitter = |k: usize, c: usize| 0.1 * (((k * 7919 + c * 104_729) % 1000) as f64 / 1e3 - 0.5);
    let off = 1.15 * (side as f64 - 1.0);
    for k in 0..count {
        let (l, i, j) = (k / (side * side), (k / side) % side, k % side);
        pos.push(V::new(
            2.3 * i as f64 - off + jitter(k, 1),
            2.3 * j as f64 - off + jitter(k, 2),
            2.6 + 2.3 * l as f64 + jitter(k, 3),
        ));
        radius.push(1.0);
        density.push(4.5);
    }
    let bonds = (0..fence)
        .map(|i| Bond {
            i,
            j: (i + 1) % fence,
            length: 3.002,
        })
        .collect();
    (pos, radius, density, bonds)
}

/// Krylov steps taken from the end of the Newton run.
const KRYLOV_STEPS: usize = 5;

/// The piles' parameters with `kind`'s constraint solve.
fn params(kind: SolverKind, n: usize) -> Params<f64> {
    let mut p = Params::<f64>::new(0.2);
    p.method = Method::Overdamped;
    p.solver.kind = kind;
    p.solver.tolerance = 1e-10;
    p.solver.max_iterations = 500;
    p.wall = Some(Wall::new(0.0));
    p.contacts = Some(Contacts::new(7 * n));
    p
}

/// Per step over the window: CPU seconds, factorisations, Newton iterations, rounds,
/// rows held (contacts, wall links and bonds) at the end; then [`KRYLOV_STEPS`] Krylov
/// steps from the state at the end: the first one's products, whether all converged,
/// and per step their products and CPU seconds.
fn run(fence: usize, side: usize, count: usize, steps: usize, window: usize) -> [f64; 9] {
    let (mut pos, radius, density, bonds) = pile(fence, side, count);
    let n = pos.len();
    let p = params(SolverKind::Newton, n);
    let krylov = params(SolverKind::Krylov, n);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, bonds.len()));
    let mut kbuf = Buffers::<f64>::new(Layout::for_params(&krylov, n, bonds.len()));
    let mut ws = buf.workspace();
    let mut kws = kbuf.workspace();
    let (mut vel, mut omega, mut time) = (vec![V::ZERO; n], vec![V::ZERO; n], 0.0);
    let mut sums = [0.0; 5];
    let (mut first, mut converged, mut products, mut cpu_k) = (0.0, 1.0, 0.0, 0.0);
    let mut taken = 0;
    // Steps `0..steps` with Newton, then `KRYLOV_STEPS` with Krylov.
    for k in 0..steps + KRYLOV_STEPS {
        let timed = k + window >= steps;
        let (t, c) = (Instant::now(), cpu());
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: None,
        };
        let (params, ws) = if k < steps {
            (&p, &mut ws)
        } else {
            (&krylov, &mut kws)
        };
        let result = step_slices(state, &bonds, params, ws, &mut NoForce);
        let elapsed = match (c, cpu()) {
            (Some(a), Some(b)) => b - a,
            _ => t.elapsed().as_secs_f64(),
        };
        let r = match (result, k < steps) {
            (Ok(r), true) => r,
            (Err(e), true) => panic!("step {k}: {e}"),
            (Ok(r), false) => {
                let it = f64::from(r.iterations);
                if k == steps {
                    first = it;
                }
                (products, cpu_k, taken) = (products + it, cpu_k + elapsed, taken + 1);
                continue;
            }
            (Err(StepError::NoConvergence { iterations, .. }), false) => {
                if k == steps {
                    first = f64::from(iterations);
                }
                converged = 0.0;
                break;
            }
            (Err(e), false) => panic!("krylov: {e}"),
        };
        if timed {
            sums[0] += elapsed;
            sums[1] += f64::from(r.factorizations);
            sums[2] += f64::from(r.iterations);
            sums[3] += f64::from(r.contact_rounds);
            sums[4] = f64::from(r.contacts + r.wall_contacts) + bonds.len() as f64;
        }
    }
    let (w, kt) = (window as f64, f64::from(taken).max(1.0));
    [
        sums[0] / w,
        sums[1] / w,
        sums[2] / w,
        sums[3] / w,
        sums[4],
        first,
        converged,
        products / kt,
        cpu_k / kt,
    ]
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a count"))
        .collect();
    let (steps, window, counts) = match args[..] {
        [s, w] => (s, w.min(s), vec![100, 300]),
        [s, w, ref c @ ..] => (s, w.min(s), c.to_vec()),
        _ => (150, 50, vec![100, 300]),
    };
    let mut command = format!("cargo run --release --example pile_cost {steps} {window}");
    if args.len() > 2 {
        for c in &counts {
            command += &format!(" {c}");
        }
    }
    let mut rows = record::Recorder::new(env!("CARGO_MANIFEST_DIR"), "pile_cost", command);
    let (mut cost, mut cost_k) = (Vec::new(), Vec::new());
    for &count in &counts {
        let side = (3..).find(|s| 12 * s * s >= count).expect("a side");
        let fence = 5 * side;
        let [s, f, it, rounds, held, products, converged, per_step, cpu_k] =
            run(fence, side, count, steps, window);
        println!(
            "{count} spheres: {:.4} s a step, {f:.1} factorisations, {it:.1} Newton \
             iterations (last round), {rounds:.1} rounds a step, {held} rows held at the end; \
             Krylov from there: {products} products ({}), {per_step:.1} products and \
             {cpu_k:.4} s a step over {KRYLOV_STEPS} steps",
            s,
            match converged == 1.0 {
                true => "converged",
                false => "did not converge",
            }
        );
        let case = format!("{count} spheres");
        for (q, v) in [
            ("cpu_s_per_step", s),
            ("factorizations_per_step", f),
            ("rounds_per_step", rounds),
            ("rows_held", held),
        ] {
            rows.row("pile newton", &case, q, &format!("{v}"));
        }
        for (q, v) in [
            ("products_one_step", products),
            ("converged", converged),
            ("products_per_step", per_step),
            ("cpu_s_per_step", cpu_k),
        ] {
            rows.row("pile krylov", &case, q, &format!("{v}"));
        }
        rows.row(
            "pile krylov / newton",
            &case,
            "cpu_ratio",
            &format!("{}", cpu_k / s),
        );
        println!("{count} spheres: Krylov / Newton a step {:.2}", cpu_k / s);
        cost.push(s);
        cost_k.push(cpu_k);
    }
    if let ([first, .., last], [first_k, .., last_k]) = (&cost[..], &cost_k[..]) {
        let ratio = format!("{} / {}", counts[counts.len() - 1], counts[0]);
        println!(
            "cost ratio {ratio}: Newton {:.1}, Krylov {:.1}",
            last / first,
            last_k / first_k
        );
        rows.row(
            "pile newton",
            &ratio,
            "cost_ratio",
            &format!("{}", last / first),
        );
        rows.row(
            "pile krylov",
            &ratio,
            "cost_ratio",
            &format!("{}", last_k / first_k),
        );
    }
    rows.finish().expect("bench/results/pile_cost.csv");
}
