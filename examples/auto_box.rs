//! The constants of the cost model that `[box] method = "auto"` chooses by
//! (`host/src/scene/box_cost.rs`): one mobility product `u = M F` in a periodic box,
//! by the dense Ewald sum (`tt_product`, every pair summed on the fly) and by PSE
//! (`Pse::apply`), timed over boxes, counts and tolerances, then fitted:
//!
//! * Ewald: `t = E0 + E1 N + E2 N^2` (its splitting parameter scales with the box, so
//!   the work per pair does not depend on the box's size; the wave sums' per-sphere
//!   work is the `N` term);
//! * PSE: `t = P0 + PG M log2 M + PN N (1 + n_near) + PS N P^3`, with `M` the grid's
//!   points, `n_near` the neighbours within the real-space cutoff per sphere and `P^3`
//!   the Gaussian support's points, all from the kernel's own parameters (`Pse::new`).
//!
//! The fit minimises the relative residuals (each time weighs the same), with every
//! constant kept non-negative. Rows (each measurement and each constant) go to a CSV
//! with the commit, the machine and the command:
//!
//! ```text
//! cargo run --release --example auto_box [-- OUT.csv]   # default bench/results/auto_box.csv
//! ```
//!
//! Times are this thread's CPU time, best of three (`shared/best.rs`), on whatever
//! machine runs it.

use std::fmt::Write as _;

use hydrorattle::Real;
use hydrorattle::mobility::periodic::{Ewald, Periodic, tt_product};
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

#[path = "shared/fit.rs"]
mod fit;
use fit::{fit, misfit};

/// `n` unit spheres at random in a cube of edge `l` (overlaps allowed: equal radii
/// never nest), and forces.
fn spheres(n: usize, l: f64, seed: u64) -> (Vec<V>, Vec<f64>, Vec<V>) {
    let mut rng = Rng(seed);
    let mut v = |s: f64| f64::v3(rng.unit() * s, rng.unit() * s, rng.unit() * s);
    let pos = (0..n).map(|_| v(l)).collect();
    let force = (0..n).map(|_| v(1.0)).collect();
    (pos, vec![1.0; n], force)
}

/// The edge of a cube holding `n` unit spheres at volume fraction `phi`.
fn edge(n: usize, phi: f64) -> f64 {
    (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / phi).cbrt()
}

/// The PSE cost terms of `n` unit spheres in a cube of edge `l` at `tol`: grid points
/// `M log2 M`, `N (1 + n_near)`, `N P^3` and `M`.
fn pse_terms(pse: &Pse<f64>, n: usize, l: f64) -> [f64; 4] {
    let g = pse.grid();
    let m = (g[0] * g[1] * g[2]) as f64;
    let s = pse.support();
    let rc = pse.r_cut();
    let near = (n as f64 / (l * l * l) * 4.0 / 3.0 * std::f64::consts::PI * rc.powi(3))
        .min(n as f64 - 1.0);
    [
        m * m.log2(),
        n as f64 * (1.0 + near),
        n as f64 * (s[0] * s[1] * s[2]) as f64,
        m,
    ]
}

fn shell(cmd: &str, args: &[&str]) -> String {
    std::process::Command::new(cmd)
        .args(args)
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default()
}

fn main() -> std::io::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "bench/results/auto_box.csv".into());
    let commit = shell("git", &["rev-parse", "--short", "HEAD"]);
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let machine = format!("{model} ({} cores)", shell("nproc", &[])).replace(',', ";");
    let command = "cargo run --release --example auto_box";
    let mut csv = String::from(
        "commit,machine,command,kind,path,n,edge,tolerance,grid_points,support_points,near,seconds,constant,value\n",
    );

    // Ewald: t = E0 + E1 N + E2 N^2.
    let (mut ex, mut et) = (vec![], vec![]);
    for (n, l) in [
        (1, 10.0),
        (1, 50.0),
        (6, 20.0),
        (13, 30.0),
        (40, 40.0),
        (120, 60.0),
        (300, 80.0),
        (2, 1000.0),
    ] {
        let (pos, rad, f) = spheres(n, l, 7);
        let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.0).unwrap();
        let mut y = vec![V::ZERO; n];
        let t = best(3, || tt_product(&ew, 1.0, &pos, &rad, &f, &mut y).unwrap());
        println!("ewald N {n:>4} L {l:>5}: {t:.3e} s");
        writeln!(
            csv,
            "{commit},{machine},{command},measure,ewald,{n},{l},,,,,{t:e},,"
        )
        .unwrap();
        ex.push(vec![1.0, n as f64, (n * n) as f64]);
        et.push(t);
    }
    // PSE: lone spheres in boxes up to 50, chains' counts, suspensions.
    let (mut px, mut pt) = (vec![], vec![]);
    let cases = [
        (1, 10.0),
        (1, 25.0),
        (1, 50.0),
        (6, 20.0),
        (13, 30.0),
        (20, edge(20, 0.1)),
        (32, edge(32, 0.1)),
        (50, edge(50, 0.1)),
        (100, edge(100, 0.1)),
        (1000, edge(1000, 0.1)),
        (300, 40.0),
        (4000, edge(4000, 0.2)),
    ];
    for (n, l) in cases {
        for tol in [1e-3, 1e-6] {
            let (pos, rad, f) = spheres(n, l, 9);
            let pse = Pse::new(Periodic::new([l; 3]).unwrap(), 1.0, tol).unwrap();
            let size = pse.storage(n);
            let mut arrays = PseBuffers::new(size);
            let mut y = vec![V::ZERO; n];
            let t = best(3, || {
                let mut st = arrays.storage();
                pse.apply(Part::Both, 1.0, &pos, &rad, &f, &mut y, &mut st)
                    .unwrap();
            });
            let terms = pse_terms(&pse, n, l);
            let s = pse.support();
            println!(
                "pse N {n:>5} L {l:>7.2} tol {tol:e}: {t:.3e} s (grid {:?}, P {}, near {:.1})",
                pse.grid(),
                s[0],
                terms[1] / n as f64 - 1.0
            );
            writeln!(
                csv,
                "{commit},{machine},{command},measure,pse,{n},{l},{tol:e},{},{},{},{t:e},,",
                terms[3],
                s[0] * s[1] * s[2],
                terms[1] / n as f64 - 1.0
            )
            .unwrap();
            px.push(vec![1.0, terms[0], terms[1], terms[2]]);
            pt.push(t);
        }
    }
    let e = fit(&ex, &et);
    let p = fit(&px, &pt);
    let names = [
        ("EWALD_FIXED", e[0]),
        ("EWALD_SPHERE", e[1]),
        ("EWALD_PAIR", e[2]),
        ("PSE_FIXED", p[0]),
        ("PSE_GRID", p[1]),
        ("PSE_NEAR", p[2]),
        ("PSE_SPREAD", p[3]),
    ];
    for (name, v) in names {
        println!("{name} = {v:.3e}");
        writeln!(
            csv,
            "{commit},{machine},{command},constant,,,,,,,,,{name},{v:.3e}"
        )
        .unwrap();
    }
    println!(
        "worst misfit: Ewald x{:.2}, PSE x{:.2}",
        misfit(&ex, &et, &e),
        misfit(&px, &pt, &p)
    );
    let tmp = format!("{out}.tmp");
    std::fs::write(&tmp, csv)?;
    std::fs::rename(tmp, out)
}
