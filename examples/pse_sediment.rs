//! A periodic suspension sedimenting with hard contacts on the PSE path:
//! unit spheres of density 4.5 in a fluid of density 0 and viscosity 1 under `|g| = 1`
//! (free Stokes speed `U0 = 2/9 (4.5) = 1`), placed at random without overlap at volume
//! fraction `phi` in a cubic box, stepped by `Overdamped` (matrix-free, Krylov, hard
//! contacts). Every step is checked for overlap by this example's own cell list (and
//! refused by the kernel's acceptance). The mean settling speed `U` is the mean of
//! `-dz/dt` over spheres and steps, relative to the zero-mean suspension velocity (the
//! box's `k = 0` mode is excluded); Richardson-Zaki's `(1 - phi)^5.1` is printed beside
//! it as a reference, not a test.
//!
//! ```text
//! cargo run --release --example pse_sediment                   # N = 1e4, phi 0.1, 100 steps
//! cargo run --release --example pse_sediment -- big 2000 20    # N = 2000, 20 steps
//! cargo run --release --example pse_sediment -- compare        # PSE vs Ewald, N = 100
//! cargo run --release --example pse_sediment -- trend          # U/U0 against phi, N = 1000
//! ```
//!
//! Times are wall-clock on whatever machine runs it (the development machine is shared).

use std::time::Instant;

use hydrorattle::integrate::pse_storage;
use hydrorattle::{
    Contacts, Layout, Method, NoForce, Params, Periodic, Real, SolverKind, State, step_slices,
};
use hydrorattle_heap::{Buffers, PseBuffers};

type V = <f64 as Real>::V3;

#[path = "shared/cpu.rs"]
mod cpu;
use cpu::cpu;

#[path = "shared/splitmix.rs"]
mod splitmix;
use splitmix::Rng;

/// A cell list of edge `>= 2` over the box `l` (unit spheres): the pairs closer than
/// `cut` by the minimum image, from the neighbouring cells only.
fn close_pairs(pos: &[[f64; 3]], l: f64, cut: f64) -> Vec<(usize, usize, f64)> {
    let m = ((l / 2.0).floor() as usize).max(1);
    let h = l / m as f64;
    let cell = |p: [f64; 3]| p.map(|x| ((x.rem_euclid(l) / h) as usize).min(m - 1));
    let mut heads = vec![Vec::new(); m * m * m];
    for (i, &p) in pos.iter().enumerate() {
        let [a, b, c] = cell(p);
        heads[(a * m + b) * m + c].push(i);
    }
    let mut out = vec![];
    for (i, &p) in pos.iter().enumerate() {
        let [a, b, c] = cell(p);
        let near = |d: usize, k: isize| (d as isize + k).rem_euclid(m as isize) as usize;
        let mut seen = vec![];
        for da in -1..=1 {
            for db in -1..=1 {
                for dc in -1..=1 {
                    let k = (near(a, da) * m + near(b, db)) * m + near(c, dc);
                    if seen.contains(&k) {
                        continue; // Fewer than 3 cells on an axis.
                    }
                    seen.push(k);
                    for &j in heads[k].iter().filter(|&&j| j > i) {
                        let d = [0, 1, 2].map(|x| {
                            let r = p[x] - pos[j][x];
                            r - l * (r / l).round()
                        });
                        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                        if r < cut {
                            out.push((i, j, r));
                        }
                    }
                }
            }
        }
    }
    out
}

/// `n` unit spheres at volume fraction `phi`, apart by at least `0.05`: box edge and
/// positions (random sequential addition).
fn suspension(n: usize, phi: f64, seed: u64) -> (f64, Vec<[f64; 3]>) {
    let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / phi).cbrt();
    let mut rng = Rng(seed);
    let m = ((l / 2.05).floor() as usize).max(1);
    let h = l / m as f64;
    let mut grid: Vec<Vec<[f64; 3]>> = vec![Vec::new(); m * m * m];
    let mut pos = Vec::with_capacity(n);
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| rng.unit() * l);
        let c = p.map(|x| ((x / h) as usize).min(m - 1));
        let mut ok = true;
        'cells: for da in -1..=1isize {
            for db in -1..=1isize {
                for dc in -1..=1isize {
                    let w = |d: usize, k: isize| (d as isize + k).rem_euclid(m as isize) as usize;
                    let k = (w(c[0], da) * m + w(c[1], db)) * m + w(c[2], dc);
                    for q in &grid[k] {
                        let d = [0, 1, 2].map(|x| {
                            let r = p[x] - q[x];
                            r - l * (r / l).round()
                        });
                        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < 2.05 * 2.05 {
                            ok = false;
                            break 'cells;
                        }
                    }
                }
            }
        }
        if ok {
            grid[(c[0] * m + c[1]) * m + c[2]].push(p);
            pos.push(p);
        }
    }
    (l, pos)
}

/// What a run measured.
struct Run {
    /// Mean settling speed over spheres and steps.
    u: f64,
    /// Final positions.
    end: Vec<[f64; 3]>,
    /// Wall-clock seconds per step (the example's overlap check included).
    per_step: f64,
    /// This thread's CPU seconds per step, in the kernel's step alone (`None` off
    /// Linux).
    cpu_step: Option<f64>,
    /// Most contacts held in a step, and the smallest gap seen (`r - 2`).
    contacts: u32,
    gap: f64,
    /// Active-set rounds (constraint solves) per step, mean and most.
    rounds: (f64, u32),
}

/// `steps` steps from `start` in the box `l`, PSE at `tol` or Ewald (`None`).
fn run(l: f64, start: &[[f64; 3]], tol: Option<f64>, steps: usize) -> Run {
    let n = start.len();
    let mut p = Params::<f64>::new(0.05);
    p.method = Method::Overdamped;
    p.matrix_free = true;
    p.solver.kind = SolverKind::Krylov;
    p.solver.tolerance = 1e-8;
    p.contacts = Some(Contacts::new(n));
    p.periodic = Some(Periodic::new([l; 3]).unwrap());
    p.pse = tol;
    let mut pos: Vec<V> = start.iter().map(|&r| f64::v3_from(r)).collect();
    let (mut vel, mut omega) = (vec![V::ZERO; n], vec![V::ZERO; n]);
    let (radius, density) = (vec![1.0; n], vec![4.5; n]);
    let mut time = 0.0;
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, 0));
    let size = pse_storage(&p, &radius).unwrap();
    let mut arrays = PseBuffers::for_step(size);
    let mut ws = arrays.attach(buf.workspace());
    let (mut sum, mut contacts, mut gap) = (0.0, 0, f64::INFINITY);
    let (mut rounds, mut most_rounds) = (0, 0);
    let mut cpu_sum = Some(0.0);
    let t0 = Instant::now();
    for k in 0..steps {
        let before: Vec<f64> = pos.iter().map(|r| r.z).collect();
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: None,
        };
        let c0 = cpu();
        let r = step_slices(state, &[], &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        let c1 = cpu();
        cpu_sum = match (cpu_sum, c0, c1) {
            (Some(s), Some(a), Some(b)) => Some(s + b - a),
            _ => None,
        };
        if n >= 1000 {
            // Large runs are long: each step on stderr as it ends.
            eprintln!(
                "step {k}: {} contacts, {} rounds, {} solver iterations, {:.2} s CPU",
                r.contacts,
                r.contact_rounds,
                r.iterations,
                c0.zip(c1).map_or(f64::NAN, |(a, b)| b - a)
            );
        }
        contacts = contacts.max(r.contacts);
        rounds += r.contact_rounds;
        most_rounds = most_rounds.max(r.contact_rounds);
        sum += pos.iter().zip(&before).map(|(r, z)| z - r.z).sum::<f64>() / (n as f64 * 0.05);
        let now: Vec<[f64; 3]> = pos.iter().map(|r| r.to_array()).collect();
        for (i, j, r) in close_pairs(&now, l, 2.0 + 1e-3) {
            gap = gap.min(r - 2.0);
            assert!(
                r > 2.0 * (1.0 - 1e-7),
                "step {k}: {i} and {j} overlap at {r}"
            );
        }
    }
    Run {
        u: sum / steps as f64,
        end: pos.iter().map(|r| r.to_array()).collect(),
        per_step: t0.elapsed().as_secs_f64() / steps as f64,
        cpu_step: cpu_sum.map(|s| s / steps as f64),
        contacts,
        gap,
        rounds: (f64::from(rounds) / steps as f64, most_rounds),
    }
}

fn rz(phi: f64) -> f64 {
    (1.0 - phi).powf(5.1)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |k: usize, d: usize| args.get(k).and_then(|a| a.parse().ok()).unwrap_or(d);
    match args.first().map(String::as_str) {
        Some("compare") => {
            let (l, start) = suspension(100, 0.1, 3);
            let e = run(l, &start, None, 10);
            println!("N = 100, phi = 0.1, box {l:.3}, 10 steps");
            println!(
                "Ewald: U/U0 = {:.5}  ({:.3} s/step, {} contacts at most, smallest gap {:.2e})",
                e.u, e.per_step, e.contacts, e.gap
            );
            for tol in [1e-3, 1e-4, 1e-6] {
                let s = run(l, &start, Some(tol), 10);
                let moved = e
                    .end
                    .iter()
                    .zip(&start)
                    .map(|(a, b)| dist(*a, *b))
                    .fold(0.0, f64::max);
                let diff = e
                    .end
                    .iter()
                    .zip(&s.end)
                    .map(|(a, b)| dist(*a, *b))
                    .fold(0.0, f64::max);
                println!(
                    "PSE {tol:e}: U/U0 = {:.5}  ({:.3} s/step, {} contacts), end positions vs Ewald {:.2e} of the largest displacement",
                    s.u,
                    s.per_step,
                    s.contacts,
                    diff / moved
                );
            }
            println!("Richardson-Zaki (1 - phi)^5.1 = {:.5}", rz(0.1));
        }
        Some("trend") => {
            let n = arg(1, 1000);
            println!("N = {n}, PSE 1e-3, 10 steps; U/U0 against Richardson-Zaki (1 - phi)^5.1");
            for phi in [0.01, 0.02, 0.05, 0.1, 0.15, 0.2] {
                let (l, start) = suspension(n, phi, 5);
                let s = run(l, &start, Some(1e-3), 10);
                println!(
                    "phi {phi:.2}: U/U0 = {:.4}   RZ {:.4}   ({:.2} s/step, {} contacts at most)",
                    s.u,
                    rz(phi),
                    s.per_step,
                    s.contacts
                );
            }
        }
        _ => {
            let (n, steps) = (arg(1, 10_000), arg(2, 100));
            let t = Instant::now();
            let (l, start) = suspension(n, 0.1, 1);
            println!(
                "N = {n}, phi = 0.1, box {l:.2} (placed in {:.1} s)",
                t.elapsed().as_secs_f64()
            );
            let s = run(l, &start, Some(1e-3), steps);
            println!(
                "PSE 1e-3, {steps} steps: U/U0 = {:.4} (RZ {:.4}), {:.3} s/step wall ({:.3} s CPU in the step), {} contacts at most, smallest gap {:.2e}, {:.1} active-set rounds a step ({} at most), no overlap at any step",
                s.u,
                rz(0.1),
                s.per_step,
                s.cpu_step.unwrap_or(f64::NAN),
                s.contacts,
                s.gap,
                s.rounds.0,
                s.rounds.1
            );
        }
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt()
}
