//! Tests of the free-space cost model: the choice at known points, what each path can
//! run, the storage limit, monotone growth in N, the near-pair estimate against exact
//! counts, and the constants against their record.

use super::free_cost::*;
use super::sizing::Plan;
use super::*;

const GIB: usize = 1 << 30;

/// An overdamped deterministic plan in free space (the Krylov solver unless `solver`
/// says otherwise).
fn plan(method: Method, solver: Solver) -> Plan {
    Plan::free(method, solver)
}

fn overdamped() -> Plan {
    plan(Method::Overdamped, Solver::Krylov)
}

/// `n` unit spheres in a ball at volume fraction `phi` (its bounding cube).
fn cloud(n: usize, phi: f64) -> Spheres {
    let r = (n as f64 / phi).cbrt();
    Spheres {
        n,
        bonds: 0,
        extent: [2.0 * r; 3],
        a_max: 1.0,
        rpy: true,
    }
}

/// A straight chain of `n` touching unit beads, bonded.
fn chain(n: usize) -> Spheres {
    Spheres {
        n,
        bonds: n - 1,
        extent: [2.0 * (n - 1) as f64, 0.0, 0.0],
        a_max: 1.0,
        rpy: true,
    }
}

fn pick(p: &Plan, s: &Spheres, limit: usize) -> FreeChoice {
    choose(p, s, 1e-4, limit).unwrap().0
}

/// The stored mobility for small constrained systems (one assembly serves the solve's
/// twenty-odd products), the fast product for a cloud of 1e5 spheres (the only path
/// whose storage and time are `O(N log N)`; dense would need 240 GB).
#[test]
fn the_choice_at_known_points() {
    for n in [2, 6, 25, 100] {
        let c = pick(&overdamped(), &chain(n), 8 * GIB);
        assert_eq!(c, FreeChoice::Dense, "chain of {n}");
    }
    // The shipped chains' default solver (Newton at their size) reads a stored metric.
    let newton = plan(Method::Overdamped2, Solver::Auto);
    assert_eq!(pick(&newton, &chain(25), 8 * GIB), FreeChoice::Dense);
    for phi in [0.01, 0.1, 0.3] {
        let s = cloud(100_000, phi);
        assert_eq!(
            pick(&overdamped(), &s, 8 * GIB),
            FreeChoice::Fast,
            "phi {phi}"
        );
        let bonded = Spheres { bonds: 1000, ..s };
        assert_eq!(
            pick(&overdamped(), &bonded, 8 * GIB),
            FreeChoice::Fast,
            "phi {phi}"
        );
    }
}

/// Methods that factorise or keep a second mobility run dense at any size, and are
/// refused (naming their need) when the dense storage does not fit; Cholesky noise,
/// a wall keep what they need; with rotation the fast path runs (its grand product
/// gives the spins).
#[test]
fn what_each_path_can_run() {
    let s = cloud(20_000, 0.1);
    for method in [Method::Rattle, Method::RattleStable, Method::Overdamped2] {
        let p = plan(method, Solver::Krylov);
        assert_eq!(pick(&p, &s, 64 * GIB), FreeChoice::Dense, "{method:?}");
        let e = choose(&p, &s, 1e-4, GIB).unwrap_err();
        assert!(e.bytes.is_some_and(|b| b > GIB), "{method:?}: {e:?}");
    }
    let mut thermal = overdamped();
    thermal.brownian = Some(Thermal {
        temperature: 1.0,
        seed: 1,
        drift: Drift::Midpoint,
        sqrt: Sqrt::Cholesky,
    });
    assert_eq!(pick(&thermal, &s, 64 * GIB), FreeChoice::Dense);
    let mut spinning = overdamped();
    spinning.rotation = true;
    // Rotation: the fast path's grand product gives the spins.
    assert_eq!(pick(&spinning, &s, 64 * GIB), FreeChoice::Fast);
    let oseen = Spheres { rpy: false, ..s };
    assert_ne!(pick(&overdamped(), &oseen, 64 * GIB), FreeChoice::Fast);
    // Bonds with the Newton solver: only the stored metric.
    let newton = plan(Method::Overdamped, Solver::Newton);
    let bonded = Spheres { bonds: 10, ..s };
    assert_eq!(pick(&newton, &bonded, 64 * GIB), FreeChoice::Dense);
}

/// A choice whose storage passes the limit is never taken: 5,000 constrained spheres
/// take a stored path (600 MB; from 700 spheres the Krylov solve reads the compact
/// copy) with room, and under a limit of 100 MB the matrix-free or fast paths.
#[test]
fn storage_limits_the_choice() {
    let cloud = Spheres {
        bonds: 100,
        ..cloud(5000, 0.1)
    };
    for s in [chain(5000), cloud] {
        let p = overdamped();
        let dense = storage(&p, &s, 1e-4, FreeChoice::Dense).unwrap();
        assert!(dense > 500_000_000, "{dense}");
        let stored = pick(&p, &s, 64 * GIB);
        assert!(
            matches!(stored, FreeChoice::Dense | FreeChoice::Compact),
            "{s:?}: {stored:?}"
        );
        let c = pick(&p, &s, 100_000_000);
        assert!(
            matches!(c, FreeChoice::MatrixFree | FreeChoice::Fast),
            "{c:?}"
        );
        let need = storage(&p, &s, 1e-4, c).unwrap();
        assert!(need <= 100_000_000, "{need}");
    }
}

/// Each path's modelled step grows with N (the fast one within its grid's steps: the
/// padded grid's edges are sizes the transforms like, so a few more spheres can take a
/// grid a few percent smaller), and the choice moves one way: from the stored mobility
/// to the products that store nothing, never back.
#[test]
fn monotone_in_n() {
    let rank = |c: FreeChoice| match c {
        FreeChoice::Dense | FreeChoice::Compact => 0,
        FreeChoice::MatrixFree => 1,
        FreeChoice::Fast => 2,
    };
    for phi in [0.01, 0.1, 0.3] {
        for bonds in [0, 50] {
            let mut last = (0, [0.0; 4]);
            for k in 0..=40 {
                let n = (10.0 * 10f64.powf(k as f64 / 10.0)) as usize;
                let s = Spheres {
                    bonds: bonds.min(n - 1),
                    ..cloud(n, phi)
                };
                let p = overdamped();
                let cost = FreeCost::of(&s, 1e-4);
                let times = CHOICES.map(|c| step_cost(&p, &s, &cost, c).unwrap_or(0.0));
                for (c, (t, t0)) in CHOICES.iter().zip(times.iter().zip(last.1)) {
                    let slack = if *c == FreeChoice::Fast { 0.85 } else { 1.0 };
                    assert!(*t >= slack * t0, "{c:?} at N {n}, phi {phi}: {t} < {t0}");
                }
                let r = rank(pick(&p, &s, 64 * GIB));
                assert!(r >= last.0, "N {n}, phi {phi}, bonds {bonds}: back to {r}");
                last = (r, times);
            }
        }
    }
}

/// The near-pair estimate against exact counts: a straight chain of spacing 2 (each
/// bead sees `r_c / 2` on each side) and a filled cube (the ball's volume over the
/// cube's).
#[test]
fn near_pairs_match_their_shapes() {
    let (n, r) = (1000, 9.0);
    let exact = (1..=4).map(|k| n - k).sum::<usize>() as f64;
    let est = near_pairs(n, [2.0 * (n - 1) as f64, 0.0, 0.0], 1.0, r);
    assert!((est / exact - 1.0).abs() < 0.15, "{est} vs {exact}");
    let l = 100.0;
    let est = near_pairs(n, [l, l, l], 1e-9, 5.0);
    let ball = 4.0 / 3.0 * std::f64::consts::PI * 125.0 / (l * l * l);
    let want = 0.5 * (n * (n - 1)) as f64 * ball;
    assert!((est / want - 1.0).abs() < 1e-6, "{est} vs {want}");
}

/// The constants in the code are the last recorded fit (`bench/results/free_cost.csv`).
#[test]
fn the_constants_are_the_recorded_fit() {
    let csv = include_str!("../../../bench/results/free_cost.csv");
    let code = [
        ("DENSE_ASSEMBLY_FIXED", DENSE_ASSEMBLY_FIXED),
        ("DENSE_ASSEMBLY_BLOCK", DENSE_ASSEMBLY_BLOCK),
        ("DENSE_PRODUCT_FIXED", DENSE_PRODUCT_FIXED),
        ("DENSE_PRODUCT_BLOCK", DENSE_PRODUCT_BLOCK),
        ("CHOLESKY_FIXED", CHOLESKY_FIXED),
        ("CHOLESKY_CUBE", CHOLESKY_CUBE),
        ("COMPACT_COPY_FIXED", COMPACT_COPY_FIXED),
        ("COMPACT_COPY_BLOCK", COMPACT_COPY_BLOCK),
        ("COMPACT_PRODUCT_FIXED", COMPACT_PRODUCT_FIXED),
        ("COMPACT_PRODUCT_BLOCK", COMPACT_PRODUCT_BLOCK),
        ("FREE_FIXED", FREE_FIXED),
        ("FREE_BLOCK", FREE_BLOCK),
        ("SPIN_FIXED", SPIN_FIXED),
        ("SPIN_BLOCK", SPIN_BLOCK),
        ("GRAND_ASSEMBLY_FIXED", GRAND_ASSEMBLY_FIXED),
        ("GRAND_ASSEMBLY_BLOCK", GRAND_ASSEMBLY_BLOCK),
        ("FAST_FIXED", FAST_FIXED),
        ("FAST_GRID", FAST_GRID),
        ("FAST_NEAR", FAST_NEAR),
        ("FAST_SPREAD", FAST_SPREAD),
        ("GRAND_FIXED", GRAND_FIXED),
        ("GRAND_GRID", GRAND_GRID),
        ("GRAND_NEAR", GRAND_NEAR),
        ("GRAND_SPREAD", GRAND_SPREAD),
    ];
    let mut recorded = std::collections::HashMap::new();
    for row in csv.lines().skip(1).map(crate::output::csv_fields) {
        assert_eq!(row.len(), 9, "{row:?}");
        if row[5].starts_with("free-space cost model constants") {
            recorded.insert(row[7].clone(), row[8].parse::<f64>().unwrap());
        }
    }
    for (name, v) in code {
        assert_eq!(recorded.get(name), Some(&v), "{name}");
    }
}

/// The model's choice against the measured rows of `bench/results/free_cost.csv`:
/// for every cloud and count where the stored, matrix-free and fast products were all
/// timed, a step of one product and a step with a constraint solve, without and with
/// rotation, the path the model picks costs, as measured, within a fifth of the
/// measured fastest of those it could pick. The times come from the record, not from
/// the model's constants.
#[test]
fn the_choice_matches_the_measured_rows() {
    use super::box_cost::PRODUCTS_SOLVE;
    let csv = include_str!("../../../bench/results/free_cost.csv");
    // The last recorded time of each (case, path).
    let mut rows = std::collections::HashMap::<(String, String), f64>::new();
    for row in csv.lines().skip(1).map(crate::output::csv_fields) {
        if row[5].starts_with("free-space product paths")
            && let Ok(t) = row[8].parse::<f64>()
        {
            rows.insert((row[6].clone(), row[7].clone()), t);
        }
    }
    let mut checked = 0;
    for phi in ["0.01", "0.1", "0.3"] {
        for n in [10, 30, 100, 300, 1000, 3000, 10_000] {
            let case = format!("cloud {phi}, N = {n}");
            let t = |q: &str| rows.get(&(case.clone(), q.to_string())).copied();
            let (Some(asm), Some(prod), Some(mf), Some(spin)) = (
                t("dense assembly"),
                t("dense product"),
                t("matrix-free product"),
                t("spin pass"),
            ) else {
                continue;
            };
            let (Some(fast), Some(fast_g), Some(grand)) = (
                t("fast product 1e-4"),
                t("fast grand-parameter product 1e-4"),
                t("fast grand product 1e-4"),
            ) else {
                continue;
            };
            let s = cloud(n, phi.parse().unwrap());
            for rotation in [false, true] {
                for bonds in [0, 1] {
                    let k = if bonds > 0 { 1.0 + PRODUCTS_SOLVE } else { 1.0 };
                    let r = if rotation { spin } else { 0.0 };
                    let mut measured = vec![
                        (FreeChoice::Dense, asm + k * prod + r),
                        (FreeChoice::MatrixFree, k * mf + r),
                        (
                            FreeChoice::Fast,
                            if rotation {
                                k * fast_g + grand
                            } else {
                                k * fast
                            },
                        ),
                    ];
                    if let (Some(copy), Some(compact)) = (t("compact copy"), t("compact product")) {
                        measured.push((FreeChoice::Compact, asm + copy + (k - 1.0) * compact + r));
                    }
                    let mut p = overdamped();
                    p.rotation = rotation;
                    let sb = Spheres { bonds, ..s };
                    let cost = FreeCost::of(&sb, 1e-4);
                    measured.retain(|(c, _)| step_cost(&p, &sb, &cost, *c).is_some());
                    let best = measured.iter().map(|m| m.1).fold(f64::INFINITY, f64::min);
                    let pick = choose(&p, &sb, 1e-4, usize::MAX).unwrap().0;
                    let got = measured.iter().find(|m| m.0 == pick).unwrap().1;
                    assert!(
                        got <= 1.2 * best,
                        "{case}, rotation {rotation}, bonds {bonds}: the model picks {pick:?} \
                         ({got:.3e} s measured), {:.2} times the best {measured:?}",
                        got / best
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked >= 24, "{checked} cases");
}

/// [`csv_fields`](crate::output::csv_fields) undoes
/// [`csv_field`](crate::output::csv_field).
#[test]
fn csv_fields_read_what_csv_field_writes() {
    let cells = ["plain", "a, b", "say \"hi\"", "", "x\"y,z"];
    let line: Vec<String> = cells.iter().map(|c| crate::output::csv_field(c)).collect();
    assert_eq!(crate::output::csv_fields(&line.join(",")), cells);
}
