//! Where the time of a step with the iterative near field goes in a periodic box, against
//! a RPY step of the same scene, in CPU time (this thread's, so that a loaded machine's
//! waits do not count) and counts. f64, one core; random suspensions at volume fraction
//! 0.25 (radii 0.8 to 1.2), the Ewald far field, one `Overdamped` step. Modes:
//!
//! * `near_box_cost step N [REPS]` (default 1000, 3): `REPS` rounds, each timing in turn
//!   the RPY step, the iterative near step (`Params::matrix_free`) and its parts alone:
//!   the translational `mu_tt` assembly (what the RPY step assembles), the grand
//!   mobility's assembly (the near step's far field), the same grand mobility from the
//!   separate translational and rotational Ewald sums (`pair_tt` then `pair_rot` a
//!   pair: how it was assembled before the two shared one pass), and the near field's
//!   set-up (close pairs found through the cell list, corrected and factored). Prints
//!   each round's ratios to the RPY step of that round, and the counts: close pairs,
//!   conjugate-gradient iterations, far-field products.
//! * `near_box_cost work N ...` (default 250 500 1000 2000): the near field's own work
//!   against `N`: close pairs, the set-up's CPU time and its work an iteration (the
//!   conjugate gradients with a block-diagonal stand-in far field, its own time taken
//!   off), and the exponent `p` of `time ~ N^p` fitted by least squares in logs.
//!
//! Where `HYDRORATTLE_BENCH_MACHINE` names the machine, appends records to
//! `bench/results/near_box_cost.csv`.

#[path = "shared/cpu.rs"]
mod cpu;
#[path = "shared/near_store.rs"]
mod near_store;
#[path = "shared/record.rs"]
mod record;
#[path = "shared/suspension.rs"]
mod suspension;

use glam::{DMat3, DVec3};
use hydrorattle::cell::Periodic;
use hydrorattle::linalg::tri;
use hydrorattle::mobility::periodic::{Ewald, assemble_tt, pair_rot, pair_tt, self_rr, self_tt};
use hydrorattle::stokesian::{Far, NearField, SdError};
use hydrorattle::{
    BondSet, Hydro, Layout, Method, NoForce, Params, Particle, ParticleSet, StepReport, step,
};
use hydrorattle_heap::Buffers;
use near_store::Store;

/// Density of unit buoyant weight for a unit sphere (`g = 1`).
const RHO1: f64 = 3.0 / (4.0 * std::f64::consts::PI);

/// CPU seconds of `f` (this thread's) and its result.
fn timed<R>(f: impl FnOnce() -> R) -> (f64, R) {
    let t = cpu::cpu().expect("CPU time (Linux)");
    let r = f();
    (cpu::cpu().expect("CPU time") - t, r)
}

/// One `Overdamped` step of the suspension, RPY with the iterative near field or
/// without it.
fn one_step(cell: Periodic<f64>, pos: &[DVec3], rad: &[f64], near: bool) -> StepReport<f64> {
    let n = pos.len();
    let mut p = Params::new(1e-4);
    p.method = Method::Overdamped;
    p.hydro = Hydro::Rpy;
    p.periodic = Some(cell);
    p.near = near.then(NearField::default);
    p.matrix_free = near;
    let list: Vec<Particle<f64>> = (0..n)
        .map(|i| Particle::new(pos[i], rad[i], RHO1))
        .collect();
    let mut ps = ParticleSet::<f64, 2000>::from_slice(&list, false).expect("spheres");
    let bonds = BondSet::<f64, 1>::new();
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, 0));
    let mut ws = buf.workspace();
    step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).expect("step")
}

/// The grand mobility as it was assembled before its translational and rotational
/// Ewald sums shared one pass: `pair_tt` and `pair_rot` a pair, in the packed layout.
fn grand_separate(ew: &Ewald<f64>, pos: &[DVec3], rad: &[f64], out: &mut [DMat3]) {
    let n = pos.len();
    for i in 0..n {
        let (ti, ri) = (tri(i), tri(n + i));
        out[ti + i] = self_tt(ew, 1.0, rad[i]);
        out[ri + n + i] = self_rr(ew, 1.0, rad[i]);
        out[ri + i] = DMat3::ZERO;
        for j in 0..i {
            let r = pos[i] - pos[j];
            let tt = pair_tt(ew, 1.0, rad[i], rad[j], r).expect("apart");
            let (rt_ij, rt_ji, rr) = pair_rot(ew, 1.0, rad[i], rad[j], r).expect("apart");
            let rj = tri(n + j);
            out[ti + j] = tt;
            out[ri + n + j] = rr;
            out[ri + j] = rt_ij;
            out[rj + i] = rt_ji;
        }
    }
}

fn step_cost(n: usize, reps: usize, rec: &mut record::Recorder) {
    let (pos, rad, l) = suspension::suspension(n, 0.25);
    let cell = Periodic::new([l; 3]).expect("box");
    let ew = Ewald::new(cell, 1.2).expect("sums");
    let far = Far::periodic(&ew);
    let near = NearField::default();
    let table = format!(
        "near step cost, {n} spheres in a box at volume fraction 0.25, f64, one core, CPU time"
    );
    let mut tt = vec![DMat3::ZERO; tri(n)];
    let mut grand = vec![DMat3::ZERO; tri(2 * n)];
    let mut old = vec![DMat3::ZERO; tri(2 * n)];
    let mut store = Store::new(far, &pos, &rad, near);
    println!("N = {n}, edge {l:.3}");
    println!(
        "round,rpy_step_s,near_step_s,ratio,tt_assembly_s,grand_assembly_s,grand_separate_s,near_setup_s,pairs,iterations,far_products"
    );
    for round in 0..reps {
        let (rpy, _) = timed(|| one_step(cell, &pos, &rad, false));
        let (sd, r) = timed(|| one_step(cell, &pos, &rad, true));
        let (t_tt, ()) = timed(|| assemble_tt(&ew, 1.0, &pos, &rad, &mut tt).expect("tt"));
        let (t_grand, ()) = timed(|| {
            far.assemble_grand(1.0, &pos, &rad, &mut grand)
                .expect("grand")
        });
        let (t_old, ()) = timed(|| grand_separate(&ew, &pos, &rad, &mut old));
        let (setup, pairs) = timed(|| store.solver(far, &pos, &rad, near).pairs());
        // The one pass gives the separate sums' blocks, bit for bit.
        let same = grand
            .iter()
            .zip(&old)
            .all(|(a, b)| a.to_cols_array() == b.to_cols_array());
        assert!(
            same,
            "the grand mobility's blocks differ from the separate sums'"
        );
        let products = r.near_iterations + 2 * r.near_products;
        println!(
            "{round},{rpy:.2},{sd:.2},{:.2},{t_tt:.2},{t_grand:.2},{t_old:.2},{setup:.3},{pairs},{},{products}",
            sd / rpy,
            r.near_iterations
        );
        let case = format!("round {round}");
        let cells = [
            ("RPY step, CPU s", format!("{rpy:.3e}")),
            ("iterative near step, CPU s", format!("{sd:.3e}")),
            ("near step / RPY step", format!("{:.3}", sd / rpy)),
            ("mu_tt assembly, CPU s", format!("{t_tt:.3e}")),
            ("grand assembly (one pass), CPU s", format!("{t_grand:.3e}")),
            (
                "grand assembly (separate sums, before), CPU s",
                format!("{t_old:.3e}"),
            ),
            (
                "near set-up (find, correct, factor), CPU s",
                format!("{setup:.3e}"),
            ),
            ("close pairs", pairs.to_string()),
            (
                "conjugate-gradient iterations",
                r.near_iterations.to_string(),
            ),
            ("far-field products", products.to_string()),
        ];
        for (quantity, value) in cells {
            rec.row(&table, &case, quantity, &value);
        }
    }
}

/// Least-squares slope of `ln y` against `ln x`.
fn exponent(x: &[f64], y: &[f64]) -> f64 {
    let (lx, ly): (Vec<f64>, Vec<f64>) = (
        x.iter().map(|v| v.ln()).collect(),
        y.iter().map(|v| v.ln()).collect(),
    );
    let k = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / k, ly.iter().sum::<f64>() / k);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

fn work(list: &[usize], rec: &mut record::Recorder) {
    let table = "near field's own work, box at volume fraction 0.25, f64, one core, CPU time";
    let near = NearField::default();
    println!("N,close_pairs,pairs_a_sphere,setup_s,work_an_iteration_s,iterations");
    let (mut ns, mut ps, mut setups, mut its) = (vec![], vec![], vec![], vec![]);
    for &n in list {
        let (pos, rad, l) = suspension::suspension(n, 0.25);
        let ew = Ewald::new(Periodic::new([l; 3]).expect("box"), 1.2).expect("sums");
        let far = Far::periodic(&ew);
        let mut store = Store::new(far, &pos, &rad, near);
        // The best of three set-ups (CPU time, 10 ms ticks).
        let setup = (0..3)
            .map(|_| timed(|| store.solver(far, &pos, &rad, near).pairs()).0)
            .fold(f64::INFINITY, f64::min);
        let mut solver = store.solver(far, &pos, &rad, near);
        let np = solver.pairs();
        let f: Vec<DVec3> = (0..2 * n)
            .map(|k| DVec3::new((k as f64).sin(), (0.3 * k as f64).cos(), -1.0))
            .collect();
        let mut u = vec![DVec3::ZERO; 2 * n];
        // A block-diagonal far field (Stokes' self mobilities), its own time taken off.
        let mut far_time = 0.0;
        let mut diag = |x: &[DVec3], y: &mut [DVec3]| -> Result<(), SdError> {
            let (t, ()) = timed(|| {
                for k in 0..2 * n {
                    let a = rad[k % n];
                    let m = match k < n {
                        true => 1.0 / (6.0 * std::f64::consts::PI * a),
                        false => 1.0 / (8.0 * std::f64::consts::PI * a * a * a),
                    };
                    y[k] = x[k] * m;
                }
            });
            far_time += t;
            Ok(())
        };
        let (t, rep) = timed(|| {
            solver
                .product(&mut diag, &f, &mut u, 1e-10, 10_000)
                .expect("product")
        });
        let it = (t - far_time) / rep.iterations.max(1) as f64;
        println!(
            "{n},{np},{:.1},{setup:.3},{it:.4},{}",
            2.0 * np as f64 / n as f64,
            rep.iterations
        );
        let case = format!("N = {n}");
        rec.row(table, &case, "close pairs", &np.to_string());
        rec.row(
            table,
            &case,
            "near set-up (find, correct, factor), CPU s",
            &format!("{setup:.3e}"),
        );
        rec.row(
            table,
            &case,
            "near work an iteration, CPU s",
            &format!("{it:.3e}"),
        );
        ns.push(n as f64);
        ps.push(np as f64);
        setups.push(setup);
        its.push(it);
    }
    if ns.len() > 1 {
        let fits = [
            ("close pairs", exponent(&ns, &ps)),
            ("near set-up", exponent(&ns, &setups)),
            ("near work an iteration", exponent(&ns, &its)),
        ];
        for (what, p) in fits {
            println!("{what} ~ N^{p:.2}");
            rec.row(
                table,
                "fit over N",
                &format!("exponent of {what}"),
                &format!("{p:.2}"),
            );
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut rec = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "near_box_cost",
        format!(
            "cargo run --release --example near_box_cost -- {}",
            args.join(" ")
        ),
    );
    let nums: Vec<usize> = args.iter().skip(1).filter_map(|a| a.parse().ok()).collect();
    match args.first().map(String::as_str) {
        Some("step") => step_cost(
            nums.first().copied().unwrap_or(1000),
            nums.get(1).copied().unwrap_or(3),
            &mut rec,
        ),
        Some("work") => match nums.is_empty() {
            true => work(&[250, 500, 1000, 2000], &mut rec),
            false => work(&nums, &mut rec),
        },
        _ => {
            eprintln!("usage: near_box_cost step [N [REPS]] | work [N ...]");
            std::process::exit(2);
        }
    }
    if let Err(e) = rec.finish() {
        eprintln!("recording failed: {e}");
    }
}
