//! Tests of the free-space cost model's thermal steps and of its choice past 10^4
//! spheres: the choice against the measured Brownian steps, the Lanczos iterations'
//! constants against their record, and the stored paths never taken where their
//! storage passes the limit.

use super::free_cost::*;
use super::free_cost_tests::{cloud, helix};
use super::free_noise;
use super::free_pick_tests::{Picks, SHAPES, cells};
use super::sizing::{DEFAULT_LIMIT, Plan};
use super::*;

/// The measured table of `examples/free_brownian.rs`.
const BROWNIAN: &str = "free-space Brownian steps, unit spheres, f64, one thread, CPU seconds a step (best of two; past 1e4 the first step)";
/// The storage past which the example times no path (its `MAX_BYTES`).
const BROWNIAN_BYTES: usize = 1_000_000_000;

/// A thermal overdamped plan in free space: the defaults of `[brownian]` (the midpoint
/// drift, the noise's square root by the kernel's crossover).
fn thermal() -> Plan {
    let mut p = Plan::free(Method::Overdamped, Solver::Krylov);
    p.brownian = Some(Thermal {
        temperature: 1.0,
        seed: 1,
        drift: Drift::Midpoint,
        sqrt: Sqrt::Auto,
    });
    p
}

/// The model's choice for a thermal step against every measured Brownian step
/// (`examples/free_brownian.rs`: every shape, N = 10 to 1e4 and the cloud at 0.1 past
/// it; whole steps, CPU seconds): the path it picks costs, as measured, at most a fifth
/// more than the fastest measured path the step ran (a step the kernel refused does
/// not count as run), within the storage the example times. The times are the
/// record's whole steps, not composed by the model: the test fails where the model's
/// form (the midpoint, the Cholesky factor, the iterations) or its constants pick the
/// wrong path.
#[test]
fn the_brownian_choice_matches_the_measured_steps() {
    let rows = cells(BROWNIAN);
    let paths = [
        (FreeChoice::Dense, "dense"),
        (FreeChoice::MatrixFree, "matrix-free"),
        (FreeChoice::Fast, "fast 1e-4"),
    ];
    let mut picks = Picks::default();
    for (shape, phi) in SHAPES {
        for n in [10, 30, 100, 300, 1000, 3000, 10_000, 20_000, 50_000] {
            let case = format!("{shape}, N = {n}");
            let s = phi.map_or_else(|| helix(n), |phi| cloud(n, phi));
            let p = thermal();
            let measured: Vec<(FreeChoice, f64)> = paths
                .iter()
                .filter_map(|&(c, name)| {
                    let v = rows.get(&(case.clone(), format!("{name} Brownian step")))?;
                    Some((c, v.parse::<f64>().ok()?))
                })
                .collect();
            // A step the kernel refused: the path cannot run there.
            let refused = paths.iter().any(|&(_, name)| {
                rows.get(&(case.clone(), format!("{name} Brownian step")))
                    .is_some_and(|v| v.starts_with("refused"))
            });
            if measured.is_empty() || (measured.len() < 2 && !refused) {
                continue;
            }
            let pick = choose(&p, &s, 1e-4, BROWNIAN_BYTES).unwrap().0;
            picks.check(&case, pick, &measured);
        }
    }
    picks.assert_all(20);
}

/// The modelled Lanczos iterations against every recorded count, within a factor 1.4 (the
/// fit's form against the measurements: the midpoint's inverse root on the pair paths,
/// the root alone on the fast path).
#[test]
fn the_iterations_follow_the_record() {
    let rows = cells(BROWNIAN);
    let mut checked = 0;
    for (shape, phi) in SHAPES {
        for n in [10, 30, 100, 300, 1000, 3000, 10_000, 20_000, 50_000] {
            let case = format!("{shape}, N = {n}");
            let s = phi.map_or_else(|| helix(n), |phi| cloud(n, phi));
            for (name, midpoint) in [("matrix-free", true), ("fast 1e-4", false)] {
                let q = format!("{name} Brownian step: Lanczos iterations");
                let Some(m) = rows.get(&(case.clone(), q)) else {
                    continue;
                };
                let m: f64 = m.parse().unwrap();
                let model = free_noise::iterations(&s, midpoint);
                assert!(
                    (model / m).ln().abs() < 1.4f64.ln(),
                    "{case}, {name}: {model:.1} modelled, {m} measured"
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 20, "{checked}");
}

/// The constants in the code are the last recorded fit (`bench/results/free_cost.csv`).
#[test]
fn the_iteration_constants_are_the_recorded_fit() {
    let csv = include_str!("../../../bench/results/free_cost.csv");
    let code = [
        ("MIDPOINT_FIXED", free_noise::MIDPOINT_FIXED),
        ("MIDPOINT_SPREAD", free_noise::MIDPOINT_SPREAD),
        ("MIDPOINT_FILL", free_noise::MIDPOINT_FILL),
        ("MIDPOINT_MISFIT", free_noise::MIDPOINT_MISFIT),
        ("ROOT_FIXED", free_noise::ROOT_FIXED),
        ("ROOT_SPREAD", free_noise::ROOT_SPREAD),
        ("ROOT_FILL", free_noise::ROOT_FILL),
        ("ROOT_MISFIT", free_noise::ROOT_MISFIT),
    ];
    let mut recorded = std::collections::HashMap::new();
    for row in csv.lines().skip(1).map(crate::output::csv_fields) {
        if row[5].starts_with("free-space Lanczos iterations model constants") {
            recorded.insert(row[7].clone(), row[8].parse::<f64>().unwrap());
        }
    }
    for (name, v) in code {
        assert_eq!(recorded.get(name), Some(&v), "{name}");
    }
}

/// Past 10^4 spheres the stored mobility (48 bytes a packed block: 9.6 GB at 2e4) is
/// over the run's limit: `auto` never takes a stored path there, for any shape, with or
/// without noise, rotation or bonds, and what it takes fits the limit. The storage is
/// what the choice weighs before the run allocates anything.
#[test]
fn past_ten_thousand_no_stored_path() {
    for n in [20_000, 50_000, 100_000] {
        for s in [cloud(n, 0.01), cloud(n, 0.1), cloud(n, 0.3), helix(n)] {
            for (noise, rotation, bonds) in [
                (false, false, 0),
                (true, false, 0),
                (false, true, 0),
                (false, false, 100),
            ] {
                let mut p = if noise {
                    thermal()
                } else {
                    Plan::free(Method::Overdamped, Solver::Krylov)
                };
                p.rotation = rotation;
                let s = Spheres { bonds, ..s };
                let dense = storage(&p, &s, 1e-4, FreeChoice::Dense).unwrap_or(usize::MAX);
                assert!(dense > DEFAULT_LIMIT, "N {n}: {dense}");
                let (c, _) = choose(&p, &s, 1e-4, DEFAULT_LIMIT).unwrap_or_else(|e| {
                    panic!("N {n}, {s:?}, noise {noise}, rotation {rotation}: {e:?}")
                });
                assert!(
                    matches!(c, FreeChoice::MatrixFree | FreeChoice::Fast),
                    "N {n}, {s:?}, noise {noise}, rotation {rotation}: {c:?}"
                );
                let need = storage(&p, &s, 1e-4, c).unwrap();
                assert!(need <= DEFAULT_LIMIT, "N {n}: {c:?} needs {need}");
            }
        }
    }
}
