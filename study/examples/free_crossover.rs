//! The chart of the free-space products' cost against N (`docs/free_crossover.png`):
//! the measured seconds a call of each path (`bench/results/free_cost.csv`, written by
//! `cargo run --release --example free_cost`) for one shape, and the crossovers where
//! the cost model (`hydrorattle_host::scene::free_cost`) that `auto` chooses by turns
//! from the stored mobility to the fast product, for a step of one product and for a
//! step with a constraint solve.
//!
//! ```text
//! cargo run --release -p hydrorattle-study --example free_crossover [-- SHAPE [OUT.png]]
//! ```
//!
//! `SHAPE` is a shape of the record (`cloud 0.01`, `cloud 0.1` (default), `cloud 0.3`,
//! `chain`).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result};
use hydrorattle_host::output::csv_fields;
use hydrorattle_host::scene::free_cost::{FreeChoice, Spheres, choose};
use hydrorattle_host::scene::sizing::Plan;
use hydrorattle_host::scene::{Method, Solver};
use hydrorattle_study::render::{LineChart, Series, line_chart};

/// The measured table's name in the record.
const TABLE: &str = "free-space product paths";

/// The smallest N (on a grid of 40 a decade) at which `auto` leaves the stored
/// mobility for a cloud at volume fraction `phi`, with `bonds` bonds (a Krylov solve).
fn crossover(phi: f64, bonds: usize) -> Option<f64> {
    let plan = Plan::free(Method::Overdamped, Solver::Krylov);
    (40..=200).map(|k| 10f64.powf(k as f64 / 40.0)).find(|&n| {
        let n = n as usize;
        let r = (n as f64 / phi).cbrt();
        let s = Spheres {
            n,
            bonds: bonds.min(n - 1),
            extent: [2.0 * r; 3],
            a_max: 1.0,
            rpy: true,
        };
        matches!(
            choose(&plan, &s, 1e-4, usize::MAX),
            Ok((FreeChoice::Fast, _))
        )
    })
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let shape = args.first().map_or("cloud 0.1", String::as_str);
    let out = args
        .get(1)
        .map_or("docs/free_crossover.png", String::as_str);
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let csv = std::fs::read_to_string(Path::new(root).join("bench/results/free_cost.csv"))
        .context("reading bench/results/free_cost.csv (run the free_cost example)")?;
    // The last recorded value of each (path, N) of the shape.
    let mut cells: BTreeMap<String, BTreeMap<u64, f64>> = BTreeMap::new();
    for row in csv.lines().skip(1).map(csv_fields) {
        let Some(n) = row[6].strip_prefix(&format!("{shape}, N = ")) else {
            continue;
        };
        if !row[5].starts_with(TABLE) {
            continue;
        }
        if let (Ok(n), Ok(t)) = (n.parse::<u64>(), row[8].parse::<f64>()) {
            cells.entry(row[7].clone()).or_default().insert(n, t);
        }
    }
    let get = |q: &str| cells.get(q).cloned().unwrap_or_default();
    let (asm, prod) = (get("dense assembly"), get("dense product"));
    let mut series = vec![Series {
        name: "dense: assembly and one product".into(),
        points: asm
            .iter()
            .filter_map(|(&n, a)| prod.get(&n).map(|p| (n as f64, a + p)))
            .collect(),
    }];
    for (q, name) in [
        ("dense product", "dense: each further product"),
        ("compact product", "compact: each further product"),
        ("matrix-free product", "matrix-free: a product"),
        ("fast product 1e-4", "fast, tolerance 1e-4: a product"),
        ("fast product 1e-6", "fast, tolerance 1e-6: a product"),
    ] {
        let points = get(q).iter().map(|(&n, &t)| (n as f64, t)).collect();
        series.push(Series {
            name: name.into(),
            points,
        });
    }
    let all = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let (lo, hi) = all.fold((f64::INFINITY, 0.0f64), |(l, h), t| (l.min(t), h.max(t)));
    let phi = shape
        .strip_prefix("cloud ")
        .and_then(|p| p.parse().ok())
        .unwrap_or(0.1);
    for (bonds, what) in [(0, "one product a step"), (1, "a constraint solve")] {
        if let Some(n) = crossover(phi, bonds) {
            println!("auto takes the fast product from N = {n:.0} ({what})");
            series.push(Series {
                name: format!("auto's crossover, {what}: N = {n:.0}"),
                points: vec![(n, lo), (n, hi)],
            });
        }
    }
    let chart = LineChart {
        title: format!("Free-space mobility products, {shape} of unit spheres"),
        x_label: "spheres N".into(),
        y_label: "CPU seconds a call, one thread".into(),
        log_x: true,
        log_y: true,
        series,
    };
    line_chart(Path::new(root).join(out).as_path(), &chart, (1100, 750))?;
    println!("wrote {out}");
    Ok(())
}
