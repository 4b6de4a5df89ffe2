//! The cost of the iterative Stokesian dynamics product (`stokesian::iterative`) in a
//! periodic box against the RPY far field's, and the near field's own work against `N`.
//!
//! `cargo run --release --example sd_iterative -- [N ...]` (default 250 500 1000 2000):
//! random suspensions of volume fraction 0.25 (radii uniform in 0.8..1.2, placed by
//! random sequential addition with gaps of at least 1e-3 mean radii, a fixed generator),
//! in `f64` on one core, tolerance 1e-6, default near field (cutoff 4 mean radii) and a
//! short one (cutoff 1). Prints, for each `N`:
//! * the near field alone: the close pairs, the seconds to find and factor them
//!   (`Solver::new`) and to apply them once per iteration (the product's time less its
//!   far-field products', with a block-diagonal stand-in far field so that every `N` runs);
//! * up to `N = 1000`, with the Ewald far field: the RPY `mu_tt` product matrix-free,
//!   the grand mobility's assembly and one product with it, and the SD product (its
//!   iterations, far-field products and seconds).
//!
//! With `HYDRORATTLE_BENCH_MACHINE` set, appends its rows to
//! `bench/results/near_iterative.csv`.
#[path = "shared/near_store.rs"]
mod near_store;
#[path = "shared/record.rs"]
mod record;
#[path = "shared/suspension.rs"]
mod suspension;

use std::time::Instant;

use glam::DVec3;
use hydrorattle::cell::Periodic;
use hydrorattle::linalg::tri;
use hydrorattle::mobility::periodic::{Ewald, tt_product};
use hydrorattle::stokesian::iterative::packed_product;
use hydrorattle::stokesian::{Far, NearField, SdError};
use near_store::Store;
use suspension::suspension;

/// The best of `k` runs of `f`, seconds.
fn best(k: usize, mut f: impl FnMut()) -> f64 {
    (0..k).fold(f64::INFINITY, |m, _| {
        let t = Instant::now();
        f();
        m.min(t.elapsed().as_secs_f64())
    })
}

fn main() {
    let sizes_asked: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let list = match sizes_asked.is_empty() {
        true => vec![250, 500, 1000, 2000],
        false => sizes_asked,
    };
    let args: Vec<String> = list.iter().map(|n| n.to_string()).collect();
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "near_iterative",
        format!(
            "cargo run --release --example sd_iterative -- {}",
            args.join(" ")
        ),
    );
    let table = "iterative SD product in a periodic box, phi = 0.25, f64, one core, tol 1e-6";
    let tol = 1e-6;
    for &n in &list {
        let (pos, rad, l) = suspension(n, 0.25);
        let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.2).unwrap();
        let far = Far::periodic(&ew);
        let f: Vec<DVec3> = (0..2 * n)
            .map(|k| DVec3::new((k as f64).sin(), (0.3 * k as f64).cos(), -1.0))
            .collect();
        let mut u = vec![DVec3::ZERO; 2 * n];
        for cutoff in [4.0, 1.0] {
            let near = NearField {
                cutoff,
                ..NearField::default()
            };
            let case = format!("N = {n}, cutoff {cutoff}");
            let mut store = Store::new(far, &pos, &rad, near);
            let setup = best(3, || {
                std::hint::black_box(store.solver(far, &pos, &rad, near).pairs());
            });
            let mut solver = store.solver(far, &pos, &rad, near);
            let np = solver.pairs();
            // The near field's work per iteration: a block-diagonal far field (Stokes'
            // self mobilities), its own time taken off.
            let (mut far_time, mut calls) = (0.0, 0u32);
            let mut diag = |x: &[DVec3], y: &mut [DVec3]| -> Result<(), SdError> {
                let t = Instant::now();
                for k in 0..2 * n {
                    let a = rad[k % n];
                    let m = match k < n {
                        true => 1.0 / (6.0 * std::f64::consts::PI * a),
                        false => 1.0 / (8.0 * std::f64::consts::PI * a * a * a),
                    };
                    y[k] = x[k] * m;
                }
                far_time += t.elapsed().as_secs_f64();
                calls += 1;
                Ok(())
            };
            let t = Instant::now();
            let rep = solver.product(&mut diag, &f, &mut u, tol, 10_000).unwrap();
            let own = (t.elapsed().as_secs_f64() - far_time) / rep.iterations.max(1) as f64;
            println!(
                "{case}: {np} close pairs ({:.1} a sphere), setup {:.3e} s, near work {:.3e} s an iteration ({} iterations with the diagonal far field)",
                2.0 * np as f64 / n as f64,
                setup,
                own,
                rep.iterations
            );
            rows.row(table, &case, "close pairs", &np.to_string());
            rows.row(
                table,
                &case,
                "near setup (pairs found, factored), s",
                &format!("{setup:.3e}"),
            );
            rows.row(
                table,
                &case,
                "near work an iteration, s",
                &format!("{own:.3e}"),
            );
            if n > 1000 {
                continue;
            }
            let mut grand = vec![glam::DMat3::ZERO; tri(2 * n)];
            let assembly = best(1, || {
                far.assemble_grand(1.0, &pos, &rad, &mut grand).unwrap()
            });
            let mut y = vec![DVec3::ZERO; 2 * n];
            let product = best(3, || packed_product::<f64>(&grand, n, &f, &mut y));
            let tt = best(3, || {
                tt_product(&ew, 1.0, &pos, &rad, &f[..n], &mut y[..n]).unwrap()
            });
            let mut ewald = |x: &[DVec3], y: &mut [DVec3]| -> Result<(), SdError> {
                packed_product::<f64>(&grand, n, x, y);
                Ok(())
            };
            let mut rep = None;
            let sd = best(3, || {
                rep = Some(solver.product(&mut ewald, &f, &mut u, tol, 10_000).unwrap())
            });
            let it = rep.unwrap().iterations;
            println!(
                "{case}: RPY mu_tt product (Ewald, matrix-free) {tt:.3e} s; grand assembly {assembly:.3e} s, grand product {product:.3e} s; SD product {sd:.3e} s ({it} iterations, {} far products); SD step (assembly + setup + product) / RPY step (assembly + product) = {:.2}",
                it + 2,
                (assembly + setup + sd) / (assembly + product)
            );
            rows.row(
                table,
                &case,
                "RPY mu_tt product, Ewald matrix-free, s",
                &format!("{tt:.3e}"),
            );
            rows.row(
                table,
                &case,
                "RPY grand assembly, Ewald, s",
                &format!("{assembly:.3e}"),
            );
            rows.row(
                table,
                &case,
                "RPY grand product, packed, s",
                &format!("{product:.3e}"),
            );
            rows.row(table, &case, "SD product, s", &format!("{sd:.3e}"));
            rows.row(table, &case, "SD iterations", &it.to_string());
            rows.row(
                table,
                &case,
                "(assembly + setup + SD product) / (assembly + RPY product)",
                &format!("{:.2}", (assembly + setup + sd) / (assembly + product)),
            );
        }
    }
    if let Err(e) = rows.finish() {
        eprintln!("recording failed: {e}");
    }
}
