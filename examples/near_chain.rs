//! The cost of a constrained step with Stokesian dynamics' near field: the dense
//! `M_SD` (formed, two inversions of `6n x 6n`) against the iterative product
//! (`Params::matrix_free`: the Krylov constraint solve, each of its products one
//! conjugate-gradient product of `M_SD`), on helical chains of the Figure 1 (c) kind:
//! a head of radius 2 and `N - 1` unit tails, bond `D = 1.05`, helix radius 2 and pitch
//! 7, density 4.5, settling; first-order `Overdamped`, the Krylov solver, tolerance
//! 1e-10, `dt = 0.1`, rotation, free space, f64, one core.
//!
//! `cargo run --release --example near_chain -- [N[:steps][:iter][:o2] ...]` (default
//! `25:20 200:3 1000:2:iter`): the seconds a step (mean over the steps), the
//! constraint solve's products a step, the `M_SD` products and their conjugate-gradient
//! iterations a step, the close pairs, and the largest distance between the two paths'
//! positions after the steps. `:iter` runs the iterative path alone (the dense one
//! would take minutes a step); `:o2` steps by `Overdamped2` instead (its two
//! velocity projections and two position projections, along `M_SD` at the start and
//! at the predicted point).
//!
//! With `HYDRORATTLE_BENCH_MACHINE` set, appends its rows to
//! `bench/results/near_chain.csv`.
#[path = "shared/record.rs"]
mod record;

use std::time::Instant;

use glam::DVec3;
use hydrorattle::helix::{HeadEnd, Helix};
use hydrorattle::stokesian::NearField;
use hydrorattle::{Bond, Layout, Method, NoForce, Params, Particle, SolverKind, step_slices};
use hydrorattle_heap::Buffers;

/// The chain's spheres: positions and radii.
fn chain(n: usize) -> Vec<Particle<f64>> {
    let h = Helix {
        tails: n - 1,
        head_ratio: 2.0,
        dhat: 1.05,
        radius: 2.0,
        pitch: 7.0,
        head_end: HeadEnd::Bottom,
    };
    h.positions()
        .expect("helix")
        .enumerate()
        .map(|(k, p)| Particle::new(DVec3::from_array(p), h.bead_radius(k), 4.5))
        .collect()
}

fn params(iterative: bool, method: Method) -> Params<f64> {
    let mut p = Params::new(0.1);
    p.method = method;
    p.solver.kind = SolverKind::Krylov;
    p.solver.tolerance = 1e-10;
    p.rotation = true;
    p.allow_overlap = true;
    p.near = Some(NearField::default());
    p.matrix_free = iterative;
    p
}

/// What a run of `steps` steps measured.
struct Cost {
    seconds: f64,
    krylov: f64,
    products: f64,
    pcg: f64,
    pairs: u32,
    formed: f64,
    pos: Vec<DVec3>,
}

fn run(n: usize, steps: usize, iterative: bool, method: Method) -> Cost {
    let list = chain(n);
    let mut pos: Vec<DVec3> = list.iter().map(|q| q.position).collect();
    let mut vel = vec![DVec3::ZERO; n];
    let mut omega = vec![DVec3::ZERO; n];
    let radius: Vec<f64> = list.iter().map(|q| q.radius).collect();
    let density: Vec<f64> = list.iter().map(|q| q.density).collect();
    let bonds: Vec<Bond<f64>> = (1..n)
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: (pos[i] - pos[i - 1]).length(),
        })
        .collect();
    let p = params(iterative, method);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, n - 1));
    let mut ws = buf.workspace();
    let mut time = 0.0;
    let mut c = Cost {
        seconds: 0.0,
        krylov: 0.0,
        products: 0.0,
        pcg: 0.0,
        pairs: 0,
        formed: 0.0,
        pos: Vec::new(),
    };
    let t = Instant::now();
    for k in 0..steps {
        let state = hydrorattle::State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: None,
        };
        let r = step_slices(state, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("N = {n}, iterative {iterative}: step {k}: {e}"));
        c.krylov += r.iterations as f64;
        c.products += r.near_products as f64;
        c.pcg += r.near_iterations as f64;
        c.formed += r.near_formations as f64;
        if k == 0 {
            c.pairs = r.near_pairs;
        }
    }
    let s = steps as f64;
    c.seconds = t.elapsed().as_secs_f64() / s;
    (c.krylov, c.products, c.pcg, c.formed) =
        (c.krylov / s, c.products / s, c.pcg / s, c.formed / s);
    c.pos = pos;
    c
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let asked = match args.is_empty() {
        true => vec!["25:20".to_string(), "200:3".into(), "1000:2:iter".into()],
        false => args,
    };
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "near_chain",
        format!(
            "cargo run --release --example near_chain -- {}",
            asked.join(" ")
        ),
    );
    println!(
        "N,path,steps,s a step,krylov products,M_SD products,pcg iterations,close pairs,M_SD formed,max position gap"
    );
    for a in &asked {
        let mut parts = a.split(':');
        let n: usize = parts.next().and_then(|x| x.parse().ok()).expect("N");
        let steps: usize = parts.next().and_then(|x| x.parse().ok()).unwrap_or(5);
        let flags: Vec<&str> = parts.collect();
        let only_iter = flags.contains(&"iter");
        let method = match flags.contains(&"o2") {
            true => Method::Overdamped2,
            false => Method::Overdamped,
        };
        let table = format!(
            "constrained {method:?} step with the near field, Figure 1 (c) helical chain, Krylov, tol 1e-10, dt 0.1, f64, one core"
        );
        let table = table.as_str();
        let iter = run(n, steps, true, method);
        let dense = (!only_iter).then(|| run(n, steps, false, method));
        let gap = dense.as_ref().map(|d| {
            d.pos
                .iter()
                .zip(&iter.pos)
                .map(|(a, b)| (*a - *b).length())
                .fold(0.0, f64::max)
        });
        for (name, c) in [("iterative", Some(&iter)), ("dense", dense.as_ref())] {
            let Some(c) = c else { continue };
            println!(
                "{n},{name},{steps},{:.3e},{:.1},{:.1},{:.1},{},{:.1},{}",
                c.seconds,
                c.krylov,
                c.products,
                c.pcg,
                c.pairs,
                c.formed,
                gap.map_or("-".into(), |g| format!("{g:.1e}"))
            );
            let case = format!("N = {n}, {name}, {steps} steps");
            rows.row(
                table,
                &case,
                "seconds a step",
                &format!("{:.3e}", c.seconds),
            );
            rows.row(
                table,
                &case,
                "Krylov products a step",
                &format!("{:.1}", c.krylov),
            );
            if name == "iterative" {
                rows.row(
                    table,
                    &case,
                    "M_SD products a step",
                    &format!("{:.1}", c.products),
                );
                rows.row(
                    table,
                    &case,
                    "CG iterations a step",
                    &format!("{:.1}", c.pcg),
                );
                rows.row(table, &case, "close pairs", &c.pairs.to_string());
            } else {
                rows.row(
                    table,
                    &case,
                    "M_SD formed a step",
                    &format!("{:.1}", c.formed),
                );
            }
            if let Some(g) = gap {
                rows.row(
                    table,
                    &case,
                    "largest position gap between the paths",
                    &format!("{g:.1e}"),
                );
            }
        }
        if let Some(d) = &dense {
            let case = format!("N = {n}, {steps} steps");
            let ratio = d.seconds / iter.seconds;
            println!("N = {n}: dense / iterative = {ratio:.2}");
            rows.row(
                table,
                &case,
                "dense / iterative seconds",
                &format!("{ratio:.2}"),
            );
        }
    }
    if let Err(e) = rows.finish() {
        eprintln!("not recorded: {e}");
    }
}
