//! Cost of the PSE product `u = M F` (`mobility::pse`) against N, tolerance and the
//! splitting parameter, and its crossover with the dense Ewald product
//! (`mobility::periodic::tt_product`). Unit spheres at volume fraction 0.1 in a cubic
//! box, random positions (overlaps allowed: equal radii never nest), f64, one thread.
//!
//! ```text
//! cargo run --release --example pse_scaling                 # N = 1e3, 1e4, 1e5 at tol 1e-4
//! cargo run --release --example pse_scaling -- tols         # each tolerance at N = 1e4
//! cargo run --release --example pse_scaling -- xi           # xi a = 0.3 ... 0.8 at N = 1e4
//! cargo run --release --example pse_scaling -- crossover    # PSE vs Ewald, N = 10 ... 400
//! cargo run --release --example pse_scaling -- noise        # the Brownian displacement
//! cargo run --release --example pse_scaling -- step [N...]   # a Brownian step on PSE
//! ```
//!
//! Times are the best of a few repetitions on whatever machine runs it (the development
//! machine is shared): read ratios, and the counts printed with them. With
//! `HYDRORATTLE_BENCH_MACHINE` set, appends each printed line's numbers to
//! `bench/results/large-n.csv`.

use std::time::Instant;

use hydrorattle::mobility::periodic::{Ewald, Periodic, tt_product};
use hydrorattle::mobility::pse::{Part, Pse};
use hydrorattle::{Lanczos, Noise, Real};
use hydrorattle_heap::PseBuffers;

type V = <f64 as Real>::V3;

#[path = "shared/splitmix.rs"]
mod splitmix;
use splitmix::Rng;

/// `n` unit spheres at volume fraction `phi`: the box edge, positions and forces.
fn suspension(n: usize, phi: f64, seed: u64) -> (f64, Vec<V>, Vec<f64>, Vec<V>) {
    let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / phi).cbrt();
    let mut rng = Rng(seed);
    let pos = (0..n)
        .map(|_| f64::v3(rng.unit() * l, rng.unit() * l, rng.unit() * l))
        .collect();
    let force = (0..n)
        .map(|_| f64::v3(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5))
        .collect();
    (l, pos, vec![1.0; n], force)
}

/// `n` unit spheres at volume fraction `phi` placed at random without overlap (a
/// suspension a step with contacts could hold; overlapping random spheres make the
/// mobility nearly singular): the box edge and positions. Rejection against the
/// spheres already placed in the neighbouring cells of a grid of cells at least 2 wide.
fn apart(n: usize, phi: f64, seed: u64) -> (f64, Vec<V>) {
    let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / phi).cbrt();
    let c = ((l / 2.0).floor() as usize).max(1);
    let mut cells: Vec<Vec<V>> = vec![vec![]; c * c * c];
    let mut rng = Rng(seed);
    let mut pos = Vec::with_capacity(n);
    let idx = |x: f64| (((x / l) * c as f64) as usize).min(c - 1);
    while pos.len() < n {
        let p = f64::v3(rng.unit() * l, rng.unit() * l, rng.unit() * l);
        let a = f64::v3_to_f64(p).map(idx);
        let mut free = true;
        for d in 0..27 {
            let k: Vec<usize> = (0..3)
                .map(|e| (a[e] + c + [d % 3, d / 3 % 3, d / 9][e] - 1) % c)
                .collect();
            for &q in &cells[k[0] + c * (k[1] + c * k[2])] {
                let r = f64::v3_to_f64(p - q).map(|x| x - l * (x / l).round());
                free &= r.iter().map(|x| x * x).sum::<f64>() >= 4.0;
            }
        }
        if free {
            cells[a[0] + c * (a[1] + c * a[2])].push(p);
            pos.push(p);
        }
    }
    (l, pos)
}

#[path = "shared/cpu.rs"]
mod cpu;
use cpu::cpu;

#[path = "shared/best.rs"]
mod best;
use best::best;

#[path = "shared/record.rs"]
mod record;
use record::Recorder;

/// The table of the product's rows.
const PRODUCT: &str = "PSE product in a periodic box, volume fraction 0.1, f64, one thread";

/// Heap storage for one `Pse` and `n` spheres, and the product into `out`.
struct Store(PseBuffers<f64>);
impl Store {
    fn new(pse: &Pse<f64>, n: usize) -> Self {
        Self(PseBuffers::new(pse.storage(n)))
    }
    fn apply(
        &mut self,
        pse: &Pse<f64>,
        part: Part,
        (pos, rad): (&[V], &[f64]),
        f: &[V],
        out: &mut [V],
    ) {
        let mut store = self.0.storage();
        pse.apply(part, 1.0, pos, rad, f, out, &mut store).unwrap();
    }
}

/// One PSE timing: (total, near, wave) seconds, and the parameters.
fn time_pse(n: usize, tol: f64, xi_a: f64, reps: usize) -> (f64, f64, f64, Pse<f64>) {
    let (l, pos, rad, force) = suspension(n, 0.1, 7);
    let cell = Periodic::new([l; 3]).unwrap();
    let pse = Pse::with_xi(cell, 1.0, tol, xi_a).unwrap();
    let mut store = Store::new(&pse, n);
    let mut out = vec![V::ZERO; n];
    let s = (&pos[..], &rad[..]);
    let total = best(reps, || store.apply(&pse, Part::Both, s, &force, &mut out));
    let near = best(reps, || store.apply(&pse, Part::Near, s, &force, &mut out));
    let wave = best(reps, || store.apply(&pse, Part::Wave, s, &force, &mut out));
    (total, near, wave, pse)
}

/// The scaling exponents `d ln t / d ln N` between successive sizes and overall.
fn exponents(ns: &[usize], times: &[f64]) {
    let slope =
        |i: usize, j: usize| (times[j] / times[i]).ln() / (ns[j] as f64 / ns[i] as f64).ln();
    let last = ns.len() - 1;
    let steps: Vec<String> = (0..last)
        .map(|i| format!("{}-{} {:.3}", ns[i], ns[i + 1], slope(i, i + 1)))
        .collect();
    println!(
        "exponent: {}, overall {:.3}",
        steps.join(", "),
        slope(0, last)
    );
}

fn describe(pse: &Pse<f64>, n: usize) -> String {
    let g = pse.grid();
    let points = g[0] * g[1] * g[2];
    format!(
        "grid {}^3 ({:.1} points/sphere), P {}, r_c {:.2}, storage {:.0} MB",
        g[0],
        points as f64 / n as f64,
        pse.support()[0],
        pse.r_cut(),
        (pse.storage(n).complex * 16 + pse.storage(n).index * 8) as f64 / 1e6
    )
}

/// The rows of one PSE timing (`time_pse`'s) of case `case`.
fn pse_rows(rows: &mut Recorder, case: &str, (t, near, wave): (f64, f64, f64), pse: &Pse<f64>) {
    let g = pse.grid();
    rows.row(PRODUCT, case, "product", &format!("{t:.4} s"));
    rows.row(
        PRODUCT,
        case,
        "near / wave",
        &format!("{near:.4} / {wave:.4} s"),
    );
    rows.row(
        PRODUCT,
        case,
        "grid",
        &format!("{}x{}x{}", g[0], g[1], g[2]),
    );
}

fn scaling(rows: &mut Recorder, tol: f64) {
    let ns = [1_000usize, 10_000, 100_000];
    let mut times = vec![];
    for &n in &ns {
        let reps = if n >= 100_000 { 2 } else { 4 };
        let (t, near, wave, pse) = time_pse(n, tol, 0.5, reps);
        println!(
            "N {n:>6}: {t:.4} s (near {near:.4}, wave {wave:.4}), {:.2} us/sphere; {}",
            t / n as f64 * 1e6,
            describe(&pse, n)
        );
        pse_rows(
            rows,
            &format!("N = {n}, tolerance {tol:e}"),
            (t, near, wave),
            &pse,
        );
        times.push(t);
    }
    exponents(&ns, &times);
}

fn tols(rows: &mut Recorder) {
    let n = 10_000;
    for tol in [1e-3, 1e-4, 1e-5, 1e-6] {
        let (t, near, wave, pse) = time_pse(n, tol, 0.5, 3);
        println!(
            "tol {tol:e}: {t:.4} s (near {near:.4}, wave {wave:.4}); {}",
            describe(&pse, n)
        );
        pse_rows(
            rows,
            &format!("N = {n}, tolerance {tol:e}"),
            (t, near, wave),
            &pse,
        );
    }
}

fn xi_scan(rows: &mut Recorder) {
    let n = 10_000;
    for tol in [1e-3, 1e-4, 1e-6] {
        for xi_a in [0.3, 0.4, 0.5, 0.6, 0.8] {
            let (t, near, wave, pse) = time_pse(n, tol, xi_a, 3);
            println!(
                "tol {tol:e} xi a {xi_a}: {t:.4} s (near {near:.4}, wave {wave:.4}); {}",
                describe(&pse, n)
            );
            let case = format!("N = {n}, tolerance {tol:e}, xi a = {xi_a}");
            pse_rows(rows, &case, (t, near, wave), &pse);
        }
    }
}

fn crossover(rows: &mut Recorder) {
    for n in [10usize, 20, 50, 100, 400] {
        let (l, pos, rad, force) = suspension(n, 0.1, 7);
        let cell = Periodic::new([l; 3]).unwrap();
        let ew = Ewald::new(cell, 1.0).unwrap();
        let mut y = vec![V::ZERO; n];
        let te = best(2, || {
            tt_product(&ew, 1.0, &pos, &rad, &force, &mut y).unwrap()
        });
        for tol in [1e-3, 1e-4, 1e-6] {
            let (tp, _, _, pse) = time_pse(n, tol, 0.5, 3);
            // The accuracy reached against the Ewald sum (rounding-level).
            let mut u = vec![V::ZERO; n];
            Store::new(&pse, n).apply(&pse, Part::Both, (&pos, &rad), &force, &mut u);
            let num: f64 = u
                .iter()
                .zip(&y)
                .map(|(a, b)| (*a - *b).length_squared())
                .sum();
            let den: f64 = y.iter().map(|b| b.length_squared()).sum();
            println!(
                "N {n:>4} tol {tol:e}: Ewald {te:.4} s, PSE {tp:.4} s (ratio {:.1}), PSE error {:.2e}",
                te / tp,
                (num / den).sqrt()
            );
            let table = "PSE against the dense Ewald product, volume fraction 0.1, f64, one thread";
            let case = format!("N = {n}, tolerance {tol:e}");
            rows.row(table, &case, "Ewald", &format!("{te:.4} s"));
            rows.row(table, &case, "PSE", &format!("{tp:.4} s"));
            let error = format!("{:.2e}", (num / den).sqrt());
            rows.row(table, &case, "PSE relative error", &error);
        }
    }
}

/// The Brownian displacement (`Pse::noise`, Lanczos tolerance 1e-3) against N.
fn noise(rows: &mut Recorder) {
    let ns = [1_000usize, 10_000, 100_000];
    let mut times = vec![];
    for &n in &ns {
        let (l, pos, rad, _) = suspension(n, 0.1, 7);
        let pse = Pse::new(Periodic::new([l; 3]).unwrap(), 1.0, 1e-4).unwrap();
        let mut store = Store::new(&pse, n);
        let s = Lanczos::default();
        let (nv, ns_) = Pse::noise_storage(&s, n);
        let (mut basis, mut work) = (vec![V::ZERO; nv], vec![0.0; ns_]);
        let mut rng = Noise::new(3);
        let mut out = vec![V::ZERO; n];
        let mut iterations = 0;
        let t = best(if n >= 100_000 { 1 } else { 2 }, || {
            let mut st = store.0.storage();
            let w = (&mut basis[..], &mut work[..]);
            iterations = pse
                .noise(1.0, (&pos, &rad), &mut rng, s, &mut out, &mut st, w)
                .unwrap();
        });
        println!("N {n:>6}: noise {t:.3} s, {iterations} Lanczos iterations");
        let table =
            "PSE Brownian displacement, volume fraction 0.1, tolerance 1e-4, f64, one thread";
        let value = format!("{t:.3} s ({iterations} iterations)");
        rows.row(table, &format!("N = {n}"), "Lanczos 1e-3", &value);
        times.push(t);
    }
    exponents(&ns, &times);
}

/// A whole Brownian step on the PSE path (`Params::pse = 1e-4`, `Overdamped`,
/// matrix-free, `kT = 1`, `dt = 0.01`, no bonds, unit spheres apart at volume fraction
/// 0.1 ([`apart`]) settling under gravity, Lanczos
/// tolerance 1e-3, the default drift: without bonds the step takes PSE's uncorrected
/// draw), against N (default 1e3, 1e4, 1e5): this thread's CPU time per step (best of
/// 2, one step each) and the noise's Lanczos iterations (the near field's).
fn steps(rows: &mut Recorder, ns: &[usize]) {
    use hydrorattle::integrate::{pse_storage, step_slices};
    use hydrorattle::{Brownian, Drift, Layout, Method, NoForce, Params, State};
    for drift in [Drift::Midpoint] {
        let mut times = vec![];
        for &n in ns {
            let (l, pos0) = apart(n, 0.1, 7);
            let rad = vec![1.0; n];
            let mut p = Params::<f64>::new(0.01);
            p.method = Method::Overdamped;
            p.periodic = Some(Periodic::new([l; 3]).unwrap());
            p.matrix_free = true;
            p.allow_overlap = true;
            p.pse = Some(1e-4);
            p.brownian = Some(Brownian {
                temperature: 1.0,
                drift,
            });
            let size = pse_storage(&p, &rad).unwrap().unwrap();
            let mut arrays = PseBuffers::new(size);
            let mut buf = hydrorattle_heap::Buffers::<f64>::new(Layout::for_params(&p, n, 0));
            let mut ws = arrays.attach(buf.workspace());
            let density = vec![1.0; n];
            let (mut pos, mut vel, mut omega) = (pos0.clone(), vec![V::ZERO; n], vec![V::ZERO; n]);
            let (mut time, mut rng) = (0.0, Noise::new(11));
            let mut report = None;
            let mut one = || {
                let state = State {
                    pos: &mut pos,
                    vel: &mut vel,
                    omega: &mut omega,
                    radius: &rad,
                    density: &density,
                    time: &mut time,
                    noise: Some(&mut rng),
                };
                report = Some(step_slices(state, &[], &p, &mut ws, &mut NoForce).unwrap());
            };
            let t = (0..2)
                .map(|_| {
                    let (w, c) = (Instant::now(), cpu());
                    one();
                    match (c, cpu()) {
                        (Some(a), Some(b)) => b - a,
                        _ => w.elapsed().as_secs_f64(),
                    }
                })
                .fold(f64::INFINITY, f64::min);
            let r = report.unwrap();
            println!(
                "{drift:?} N {n:>6}: step {t:.3} s, noise iterations {}",
                r.noise_iterations
            );
            let table = "Brownian step on PSE, Overdamped, matrix-free, volume fraction 0.1, f64, one thread";
            let case = format!("N = {n}, {drift:?} drift");
            rows.row(table, &case, "CPU time a step", &format!("{t:.3} s"));
            let noise = r.noise_iterations.to_string();
            rows.row(table, &case, "noise iterations", &noise);
            times.push(t);
        }
        if ns.len() > 1 {
            exponents(ns, &times);
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut recorder = Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "large-n",
        format!(
            "cargo run --release --example pse_scaling -- {}",
            args.join(" ")
        ),
    );
    let rows = &mut recorder;
    let arg = args.first().cloned().unwrap_or_default();
    match arg.as_str() {
        "tols" => tols(rows),
        "xi" => xi_scan(rows),
        "crossover" => crossover(rows),
        "noise" => noise(rows),
        "step" => {
            let ns: Vec<usize> = std::env::args()
                .skip(2)
                .map(|s| s.parse().unwrap())
                .collect();
            steps(
                rows,
                if ns.is_empty() {
                    &[1_000, 10_000, 100_000]
                } else {
                    &ns
                },
            )
        }
        "one" => {
            let n: usize = std::env::args()
                .nth(2)
                .map_or(10_000, |s| s.parse().unwrap());
            let (t, near, wave, pse) = time_pse(n, 1e-4, 0.5, 3);
            println!(
                "N {n}: {t:.4} s (near {near:.4}, wave {wave:.4}); {}",
                describe(&pse, n)
            );
            pse_rows(
                rows,
                &format!("N = {n}, tolerance 1e-4"),
                (t, near, wave),
                &pse,
            );
        }
        _ => scaling(rows, 1e-4),
    }
    recorder
        .finish()
        .expect("appending to bench/results/large-n.csv");
}
