//! Cost of the fast free-space product `u = M F` (`mobility::free_fast`) against N, and
//! against the dense free-space product (`mobility::tt_product`) where that is
//! feasible. A cloud of unit spheres uniformly in a ball at volume fraction 0.05
//! (overlaps allowed: equal radii never nest), forces uniform in `[-1, 1]^3`, f64, one
//! thread.
//!
//! ```text
//! cargo run --release --example free_fast_scaling                  # N = 1e3, 1e4, 1e5 at tol 1e-4
//! cargo run --release --example free_fast_scaling -- 1e-6 1000 10000 # a tolerance, then N
//! ```
//!
//! Prints one CSV row per N: the setup (parameters and the kernel's transform, once per
//! cloud size), one product with the kernel kept (best of a few), the dense product
//! (up to N = 2e4) and the error against it, the storage, and the fitted exponent; times
//! are this thread's CPU seconds (a shared machine's waits left out). With
//! `HYDRORATTLE_BENCH_MACHINE` set, the rows go to `bench/results/free_fast.csv`.

use std::time::Instant;

use hydrorattle::Real;
use hydrorattle::mobility::free_fast::FreeFast;
use hydrorattle::mobility::{Hydro, tt_product};
use hydrorattle_heap::FreeBuffers;

type V = <f64 as Real>::V3;

#[path = "shared/cpu.rs"]
mod cpu;
#[path = "shared/record.rs"]
mod record;
#[path = "shared/splitmix.rs"]
mod splitmix;
use cpu::cpu;
use splitmix::Rng;

/// `n` unit spheres uniformly in a ball at volume fraction `phi`, and forces.
fn cloud(n: usize, phi: f64, seed: u64) -> (Vec<V>, Vec<V>, f64) {
    let radius = (n as f64 / phi).cbrt();
    let mut rng = Rng(seed);
    let mut pos = Vec::with_capacity(n);
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| radius * (2.0 * rng.unit() - 1.0));
        if p.iter().map(|x| x * x).sum::<f64>() <= radius * radius {
            pos.push(f64::v3_from(p));
        }
    }
    let f = (0..n)
        .map(|_| f64::v3_from([0, 1, 2].map(|_| 2.0 * rng.unit() - 1.0)))
        .collect();
    (pos, f, radius)
}

fn rel_err(a: &[V], b: &[V]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        num += f64::norm2(*x - *y);
        den += f64::norm2(*y);
    }
    (num / den).sqrt()
}

/// The best of `reps` runs of `f`: this thread's CPU seconds (10 ms ticks) where
/// Linux reports them, so a shared machine's waits are left out, else wall seconds.
fn best(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let (c0, t0) = (cpu(), Instant::now());
        f();
        let wall = t0.elapsed().as_secs_f64();
        best = best.min(cpu().zip(c0).map_or(wall, |(c1, c0)| c1 - c0));
    }
    best
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let tol: f64 = args.first().map_or(1e-4, |s| s.parse().unwrap());
    let ns: Vec<usize> = match args.len() {
        0 | 1 => vec![1000, 10_000, 100_000],
        _ => args[1..]
            .iter()
            .map(|s| s.parse::<f64>().unwrap() as usize)
            .collect(),
    };
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "free_fast",
        format!(
            "cargo run --release --example free_fast_scaling -- {}",
            args.join(" ")
        ),
    );
    let table = format!(
        "fast free-space RPY product, unit spheres in a ball at volume fraction 0.05, f64, one thread, tolerance {tol:e}, CPU seconds"
    );
    println!("n,tolerance,estimate,grid,support,r_cut,setup_s,product_s,dense_s,error,storage_mb");
    let mut fit = Vec::new();
    for &n in &ns {
        let (pos, f, radius) = cloud(n, 0.05, 7 + n as u64);
        let rad = vec![1.0; n];
        let ext = 2.0 * radius;
        // `SIGMA=<value>` overrides the rule's spreading width (to tune the rule).
        let make = || match std::env::var("SIGMA") {
            Ok(s) => FreeFast::<f64>::with_sigma(1.0, tol, [ext; 3], s.parse().unwrap()),
            Err(_) => FreeFast::<f64>::new(1.0, tol, [ext; 3], n),
        };
        let ff = make().unwrap();
        let size = ff.storage(n);
        let mut arrays = FreeBuffers::<f64>::new(size);
        let mb = arrays.bytes() as f64 / 1e6;
        let mut out = vec![f64::V3_ZERO; n];
        let mut store = arrays.storage();
        // The setup: the parameters and the kernel's transform (on a first product,
        // which keeps the kernel in the storage).
        let first = best(1, || {
            let ff = make().unwrap();
            ff.apply(1.0, &pos, &rad, &f, &mut out, &mut store).unwrap();
        });
        let reps = match n {
            ..100_000 => 3,
            100_000..1_000_000 => 2,
            _ => 1,
        };
        let product = best(reps, || {
            ff.apply(1.0, &pos, &rad, &f, &mut out, &mut store).unwrap();
        });
        let (mut dense_s, mut err) = (f64::NAN, f64::NAN);
        if n <= 20_000 {
            let mut y = vec![f64::V3_ZERO; n];
            dense_s = best(1, || {
                tt_product(Hydro::Rpy, 1.0, &pos, &rad, &f, &mut y).unwrap();
            });
            err = rel_err(&out, &y);
        }
        let g = ff.grid();
        let grid = format!("{}x{}x{}", g[0], g[1], g[2]);
        println!(
            "{n},{tol:e},{:.2e},{grid},{},{:.3},{:.3},{product:.4},{dense_s:.4},{err:.2e},{mb:.0}",
            ff.estimate(),
            ff.support(),
            ff.r_cut(),
            first - product,
        );
        let case = format!("N = {n}");
        let cells = [
            (
                "seconds, one product (kernel kept)",
                format!("{product:.4}"),
            ),
            (
                "seconds, setup (parameters and kernel transform)",
                format!("{:.3}", first - product),
            ),
            ("seconds, dense tt_product", format!("{dense_s:.4}")),
            ("relative error against dense", format!("{err:.2e}")),
            ("padded grid", grid),
            ("storage MB", format!("{mb:.0}")),
        ];
        for (q, v) in cells.iter().filter(|(_, v)| v != "NaN") {
            rows.row(&table, &case, q, v);
        }
        fit.push(((n as f64).ln(), product.ln()));
    }
    if fit.len() >= 2 {
        let k = fit.len() as f64;
        let (sx, sy) = fit.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
        let (mx, my) = (sx / k, sy / k);
        let (sxy, sxx) = fit.iter().fold((0.0, 0.0), |a, p| {
            (a.0 + (p.0 - mx) * (p.1 - my), a.1 + (p.0 - mx) * (p.0 - mx))
        });
        let e = sxy / sxx;
        println!("exponent (least squares of ln t on ln N): {e:.3}");
        let case = format!("N = {} to {}", ns[0], ns[ns.len() - 1]);
        rows.row(
            &table,
            &case,
            "fitted exponent of the product time",
            &format!("{e:.3}"),
        );
    }
    rows.finish().unwrap();
}
