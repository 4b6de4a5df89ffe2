//! The chart of the free-space products' cost against N (`docs/free_crossover.png`):
//! the measured seconds a call of each path (`bench/results/free_cost.csv`, written by
//! `cargo run --release --example free_cost`) for one shape, without and with rotation,
//! and the crossovers where the cost model (`hydrorattle_host::scene::free_cost`) that
//! `auto` chooses by turns from the stored mobility to the fast product, for a step of
//! one product and for a step with a constraint solve. Below them, in a second panel,
//! the thermal case: the measured seconds of one whole Brownian step by each path (the
//! table of `cargo run --release --example free_brownian`, in the same file) and where
//! `auto` takes the fast product for it. It prints the measured crossovers too: the N
//! (interpolated between the measured counts) from which a step on the fast product
//! costs less than on each other path.
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
use hydrorattle_host::scene::box_cost::PRODUCTS_SOLVE;
use hydrorattle_host::scene::free_cost::{FreeChoice, Spheres, choose};
use hydrorattle_host::scene::sizing::Plan;
use hydrorattle_host::scene::{DEFAULT_SEED, Drift, Method, Solver, Sqrt, Thermal};
use hydrorattle_study::render::{LineChart, Series, line_charts};

/// The measured table's name in the record (the fast products in the steady state).
const TABLE: &str = "free-space product paths, unit spheres, f64, one thread, CPU seconds a call (best of two; fast products with the kernel's transform kept)";
/// The Brownian steps' table (`examples/free_brownian.rs`).
const BROWNIAN: &str = "free-space Brownian steps, unit spheres, f64, one thread, CPU seconds a step (best of two; past 1e4 the first step)";

/// The smallest N (on a grid of 40 a decade) at which `auto` takes the fast product
/// for a cloud at volume fraction `phi`, with `bonds` bonds (a Krylov solve), with or
/// without `rotation`, deterministic or `thermal` (`[brownian]`'s defaults: the
/// midpoint drift, the kernel's choice of square root).
fn crossover(phi: f64, bonds: usize, rotation: bool, thermal: bool) -> Option<f64> {
    let mut plan = Plan::free(Method::Overdamped, Solver::Krylov);
    plan.rotation = rotation;
    plan.brownian = thermal.then_some(Thermal {
        temperature: 1.0,
        seed: DEFAULT_SEED,
        drift: Drift::Midpoint,
        sqrt: Sqrt::Auto,
    });
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

/// Measured seconds by N.
type Times = BTreeMap<u64, f64>;

/// `f` at every N where each of `parts` was measured.
fn combine(parts: &[&Times], f: impl Fn(&[f64]) -> f64) -> Times {
    let Some(first) = parts.first() else {
        return Times::new();
    };
    first
        .keys()
        .filter_map(|n| {
            let v: Option<Vec<f64>> = parts.iter().map(|p| p.get(n).copied()).collect();
            v.map(|v| (*n, f(&v)))
        })
        .collect()
}

/// The N from which `fast` costs less than `other` and stays so over the measured
/// counts (log-interpolated between the last count where it did not and the next):
/// `Some(lowest N)` where it always does, `None` where it never does.
fn measured_crossover(fast: &Times, other: &Times) -> Option<f64> {
    let both: Vec<(f64, f64)> = fast
        .iter()
        .filter_map(|(n, f)| other.get(n).map(|o| (*n as f64, (f / o).ln())))
        .collect();
    let last_worse = both.iter().rposition(|&(_, r)| r >= 0.0);
    match last_worse {
        None => both.first().map(|p| p.0),
        Some(k) if k + 1 == both.len() => None,
        Some(k) => {
            let ((n0, r0), (n1, r1)) = (both[k], both[k + 1]);
            let x = r0 / (r0 - r1);
            Some((n0.ln() + x * (n1.ln() - n0.ln())).exp())
        }
    }
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
    // The last recorded value of each (path, N) of the shape, the Brownian steps' by
    // their own names ("... Brownian step").
    let mut cells: BTreeMap<String, BTreeMap<u64, f64>> = BTreeMap::new();
    for row in csv.lines().skip(1).map(csv_fields) {
        let Some(n) = row[6].strip_prefix(&format!("{shape}, N = ")) else {
            continue;
        };
        if row[5] != TABLE && row[5] != BROWNIAN {
            continue;
        }
        if let (Ok(n), Ok(t)) = (n.parse::<u64>(), row[8].parse::<f64>()) {
            cells.entry(row[7].clone()).or_default().insert(n, t);
        }
    }
    let get = |q: &str| cells.get(q).cloned().unwrap_or_default();
    let (asm, prod, spin) = (
        get("dense assembly"),
        get("dense product"),
        get("spin pass"),
    );
    let (copy, compact, free) = (
        get("compact copy"),
        get("compact product"),
        get("matrix-free product"),
    );
    let (fast, fast_g, grand) = (
        get("fast product 1e-4"),
        get("fast grand-parameter product 1e-4"),
        get("fast grand product 1e-4"),
    );
    let points = |t: &Times| t.iter().map(|(&n, &t)| (n as f64, t)).collect();
    let mut series = vec![Series {
        name: "dense: assembly and one product".into(),
        points: points(&combine(&[&asm, &prod], |v| v[0] + v[1])),
    }];
    for (q, name) in [
        ("dense product", "dense: each further product"),
        ("compact product", "compact: each further product"),
        ("matrix-free product", "matrix-free: a product"),
        ("fast product 1e-4", "fast, tolerance 1e-4: a product"),
        ("fast product 1e-6", "fast, tolerance 1e-6: a product"),
    ] {
        series.push(Series {
            name: name.into(),
            points: points(&get(q)),
        });
    }
    series.push(Series {
        name: "rotation, dense: assembly, one product and the spins".into(),
        points: points(&combine(&[&asm, &prod, &spin], |v| v.iter().sum())),
    });
    series.push(Series {
        name: "rotation, fast 1e-4: a product and the spins (grand)".into(),
        points: points(&combine(&[&fast_g, &grand], |v| v[0] + v[1])),
    });
    // The thermal case: whole Brownian steps as measured, no composing.
    let thermal = [
        ("dense", "stored mobility"),
        ("matrix-free", "matrix-free"),
        ("fast 1e-4", "fast 1e-4"),
    ]
    .map(|(q, name)| (name, get(&format!("{q} Brownian step"))));
    let mut steps: Vec<Series> = thermal
        .iter()
        .map(|(name, t)| Series {
            name: format!("{name}: a whole Brownian step"),
            points: points(t),
        })
        .collect();
    // A product beside the steps: a step of the fast path is some twenty of them.
    steps.push(Series {
        name: "fast, tolerance 1e-4: one product (the panel above)".into(),
        points: points(&fast),
    });
    for (name, other) in &thermal[..2] {
        let at = measured_crossover(&thermal[2].1, other)
            .map_or("not within the measured counts".into(), |n| {
                format!("N = {n:.0}")
            });
        println!("{shape}, a Brownian step: fast beats {name} from {at} (measured)");
    }
    // The measured crossovers of a step of `k` products, fast against each other path.
    for (rotation, k, what) in [
        (false, 1.0, "one product a step"),
        (false, 1.0 + PRODUCTS_SOLVE, "a constraint solve"),
        (true, 1.0, "one product a step, rotation"),
        (true, 1.0 + PRODUCTS_SOLVE, "a constraint solve, rotation"),
    ] {
        let s = |t: f64| if rotation { t } else { 0.0 };
        let fast_step = match rotation {
            false => combine(&[&fast], |v| k * v[0]),
            true => combine(&[&fast_g, &grand], |v| k * v[0] + v[1]),
        };
        let spins = if rotation {
            spin.clone()
        } else {
            asm.keys().map(|n| (*n, 0.0)).collect()
        };
        let others = [
            (
                "dense",
                combine(&[&asm, &prod, &spins], |v| v[0] + k * v[1] + s(v[2])),
            ),
            (
                "compact",
                combine(&[&asm, &copy, &prod, &compact, &spins], |v| {
                    v[0] + v[1] + v[2] + (k - 1.0) * v[3] + s(v[4])
                }),
            ),
            (
                "matrix-free",
                combine(&[&free, &spins], |v| k * v[0] + s(v[1])),
            ),
        ];
        for (name, other) in others {
            let at = measured_crossover(&fast_step, &other)
                .map_or("not within the measured counts".into(), |n| {
                    format!("N = {n:.0}")
                });
            println!("{shape}, {what}: fast beats {name} from {at} (measured)");
        }
    }
    // Each panel's range of seconds, for its crossovers' vertical lines.
    let range = |series: &[Series]| {
        let all = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
        all.fold((f64::INFINITY, 0.0f64), |(l, h), t| (l.min(t), h.max(t)))
    };
    let (products, thermal_range) = (range(&series), range(&steps));
    let phi = shape
        .strip_prefix("cloud ")
        .and_then(|p| p.parse().ok())
        .unwrap_or(0.1);
    for (bonds, rotation, thermal, what) in [
        (0, false, false, "one product a step"),
        (1, false, false, "a constraint solve"),
        (0, true, false, "one product a step, rotation"),
        (1, true, false, "a constraint solve, rotation"),
        (0, false, true, "a Brownian step"),
    ] {
        if let Some(n) = crossover(phi, bonds, rotation, thermal) {
            println!("auto takes the fast product from N = {n:.0} ({what})");
            let ((lo, hi), panel) = match thermal {
                false => (products, &mut series),
                true => (thermal_range, &mut steps),
            };
            panel.push(Series {
                name: format!("auto's crossover, {what}: N = {n:.0}"),
                points: vec![(n, lo), (n, hi)],
            });
        }
    }
    let charts = [
        LineChart {
            title: format!("Free-space mobility products, {shape} of unit spheres"),
            x_label: "spheres N".into(),
            y_label: "CPU seconds a call, one thread".into(),
            log_x: true,
            log_y: true,
            series,
        },
        LineChart {
            title: format!("Thermal: one whole Brownian step, {shape} of unit spheres"),
            x_label: "spheres N".into(),
            y_label: "CPU seconds a step, one thread".into(),
            log_x: true,
            log_y: true,
            series: steps,
        },
    ];
    line_charts(Path::new(root).join(out).as_path(), &charts, (1100, 1500))?;
    println!("wrote {out}");
    Ok(())
}
