//! Cost of PSE's grand product `(U, W) = M (F, T)` (`Pse::apply_grand`) against its
//! translation product `u = M F` (`Pse::apply`) and the Ewald path's grand assembly
//! (`periodic::assemble_grand`), with the error reached against the Ewald sums. Unit
//! spheres at random positions (overlaps allowed: equal radii never nest) at volume
//! fractions 0.1 and 0.25 in a cubic box, f64, one thread.
//!
//! ```text
//! cargo run --release --example pse_grand                # N = 1e3, 1e4, tolerance 1e-4
//! cargo run --release --example pse_grand -- 1e-6        # another tolerance
//! ```
//!
//! The Ewald grand assembly is timed whole at N = 1e3; at N = 1e4 (its matrix would
//! take 14 GB) its time is its cost a pair, measured on 400 of the spheres in the same
//! box, times the pairs. The
//! error is over all rows at N = 1e3 (the assembled matrix times the loads) and over
//! 24 rows at N = 1e4 (each summed with the Ewald path's pair blocks). Times are the
//! best of a few repetitions on a shared machine: read ratios. With
//! `HYDRORATTLE_BENCH_MACHINE` set, appends the rows to `bench/results/large-n.csv`.

use hydrorattle::Real;
use hydrorattle::linalg::tri;
use hydrorattle::mobility::periodic::{
    Ewald, Periodic, assemble_grand, pair_rot, pair_tt, self_rr, self_tt,
};
use hydrorattle::mobility::pse::{Part, Pse};
use hydrorattle_heap::PseBuffers;

type V = <f64 as Real>::V3;

#[path = "shared/splitmix.rs"]
mod splitmix;
use splitmix::Rng;

#[path = "shared/cpu.rs"]
mod cpu;

#[path = "shared/best.rs"]
mod best;
use best::best;

#[path = "shared/record.rs"]
mod record;
use record::Recorder;

/// `n` unit spheres at volume fraction `phi`: the box edge, positions, and forces then
/// torques (`2n`).
fn suspension(n: usize, phi: f64, seed: u64) -> (f64, Vec<V>, Vec<V>) {
    let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / phi).cbrt();
    let mut rng = Rng(seed);
    let pos = (0..n)
        .map(|_| f64::v3(rng.unit() * l, rng.unit() * l, rng.unit() * l))
        .collect();
    let load = (0..2 * n)
        .map(|_| f64::v3(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5))
        .collect();
    (l, pos, load)
}

/// `|a - b| / |b|` over the rows given.
fn rel_err(a: &[V], b: &[V]) -> f64 {
    let num: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared())
        .sum();
    let den: f64 = b.iter().map(|y| y.length_squared()).sum();
    (num / den).sqrt()
}

/// Rows `rows` of the Ewald grand product: `(U_i, W_i)` from the pair blocks.
fn ewald_rows(ew: &Ewald<f64>, pos: &[V], x: &[V], rows: &[usize]) -> Vec<(V, V)> {
    let n = pos.len();
    let (f, t) = x.split_at(n);
    rows.iter()
        .map(|&i| {
            let mut u = self_tt(ew, 1.0, 1.0) * f[i];
            let mut w = self_rr(ew, 1.0, 1.0) * t[i];
            for j in (0..n).filter(|&j| j != i) {
                let r = pos[i] - pos[j];
                let tt = pair_tt(ew, 1.0, 1.0, 1.0, r).unwrap();
                let (rt_ij, rt_ji, rr) = pair_rot(ew, 1.0, 1.0, 1.0, r).unwrap();
                u += tt * f[j] + rt_ji.transpose() * t[j];
                w += rt_ij * f[j] + rr * t[j];
            }
            (u, w)
        })
        .collect()
}

/// The whole Ewald grand product through the assembled matrix: velocities then spins,
/// and the assembly's time.
fn ewald_all(ew: &Ewald<f64>, pos: &[V], x: &[V]) -> (Vec<V>, f64) {
    let n = pos.len();
    let rad = vec![1.0; n];
    let mut m = vec![f64::M3_ZERO; tri(2 * n)];
    let t = best(1, || assemble_grand(ew, 1.0, pos, &rad, &mut m).unwrap());
    let mut y = vec![V::ZERO; 2 * n];
    for i in 0..2 * n {
        for j in 0..=i {
            let b = m[tri(i) + j];
            y[i] += b * x[j];
            if j < i {
                y[j] += b.transpose() * x[i];
            }
        }
    }
    (y, t)
}

fn run(rows: &mut Recorder, n: usize, phi: f64, tol: f64) {
    let (l, pos, x) = suspension(n, phi, 7);
    let rad = vec![1.0; n];
    let cell = Periodic::new([l; 3]).unwrap();
    let pse = Pse::new(cell, 1.0, tol).unwrap();
    let mut arrays = PseBuffers::new(pse.storage_grand(n));
    let (f, t) = x.split_at(n);
    let mut y = vec![V::ZERO; 2 * n];
    let reps = if n >= 10_000 { 2 } else { 4 };
    let t_grand = best(reps, || {
        let mut store = arrays.storage();
        let (u, w) = y.split_at_mut(n);
        pse.apply_grand(1.0, (&pos, &rad), f, t, u, w, &mut store)
            .unwrap();
    });
    let mut u_tt = vec![V::ZERO; n];
    let t_trans = best(reps, || {
        let mut store = arrays.storage();
        pse.apply(Part::Both, 1.0, &pos, &rad, f, &mut u_tt, &mut store)
            .unwrap();
    });
    let ew = Ewald::new(cell, 1.0).unwrap();
    let (t_ewald, eu, ew_err, how) = if n <= 2_000 {
        let (want, ta) = ewald_all(&ew, &pos, &x);
        let (eu, ew_) = (rel_err(&y[..n], &want[..n]), rel_err(&y[n..], &want[n..]));
        (ta, eu, ew_, "measured")
    } else {
        let sample: Vec<usize> = (0..24).map(|k| k * (n / 24)).collect();
        let want = ewald_rows(&ew, &pos, &x, &sample);
        let got_u: Vec<V> = sample.iter().map(|&i| y[i]).collect();
        let got_w: Vec<V> = sample.iter().map(|&i| y[n + i]).collect();
        let (wu, ww): (Vec<V>, Vec<V>) = want.into_iter().unzip();
        // The assembly's cost a pair, measured on the first `m` spheres in the same box.
        let m = 400;
        let mut blocks = vec![f64::M3_ZERO; tri(2 * m)];
        let part = best(1, || {
            assemble_grand(&ew, 1.0, &pos[..m], &rad[..m], &mut blocks).unwrap()
        });
        let pairs = |k: usize| (k * (k - 1) / 2) as f64;
        let (eu, ew_) = (rel_err(&got_u, &wu), rel_err(&got_w, &ww));
        (part / pairs(m) * pairs(n), eu, ew_, "estimated")
    };
    let g = pse.grid();
    println!(
        "N {n:>5} phi {phi}: grand {t_grand:.4} s, translation {t_trans:.4} s (ratio {:.2}), Ewald grand assembly {t_ewald:.1} s ({how}); error U {eu:.2e}, W {ew_err:.2e} (tol {tol:e}); grid {}^3, P {}, r_c {:.2}",
        t_grand / t_trans,
        g[0],
        pse.support()[0],
        pse.r_cut()
    );
    let table = "PSE grand product (forces and torques) in a periodic box, f64, one thread";
    let case = format!("N = {n}, volume fraction {phi}, tolerance {tol:e}");
    rows.row(table, &case, "grand product", &format!("{t_grand:.4} s"));
    rows.row(
        table,
        &case,
        "translation product",
        &format!("{t_trans:.4} s"),
    );
    let ewald = format!("{t_ewald:.2} s ({how})");
    rows.row(table, &case, "Ewald grand assembly", &ewald);
    rows.row(
        table,
        &case,
        "error U / W",
        &format!("{eu:.2e} / {ew_err:.2e}"),
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let tol: f64 = args.first().map_or(1e-4, |s| s.parse().unwrap());
    let mut recorder = Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "large-n",
        format!(
            "cargo run --release --example pse_grand -- {}",
            args.join(" ")
        ),
    );
    for n in [1_000, 10_000] {
        for phi in [0.1, 0.25] {
            run(&mut recorder, n, phi, tol);
        }
    }
    recorder
        .finish()
        .expect("appending to bench/results/large-n.csv");
}
