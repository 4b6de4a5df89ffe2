//! Tests of the free-space cost model: the choice at known points, what each path can
//! run, the storage limit, monotone growth in N, the near-pair estimate against exact
//! counts, and the constants against their record.

use super::free_cost::*;
use super::free_pick_tests::{Picks, SHAPES, numbers};
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
pub(super) fn cloud(n: usize, phi: f64) -> Spheres {
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

/// Methods that factorise the mobility run dense at any size, and are refused (naming
/// their need) when the dense storage does not fit (`Overdamped2` runs on the fast
/// product, its two mobilities products); Cholesky noise,
/// a wall keep what they need; with rotation the fast path runs (its grand product
/// gives the spins).
#[test]
fn what_each_path_can_run() {
    let s = cloud(20_000, 0.1);
    for method in [Method::Rattle, Method::RattleStable] {
        let p = plan(method, Solver::Krylov);
        assert_eq!(pick(&p, &s, 64 * GIB), FreeChoice::Dense, "{method:?}");
        let e = choose(&p, &s, 1e-4, GIB).unwrap_err();
        assert!(e.bytes.is_some_and(|b| b > GIB), "{method:?}: {e:?}");
    }
    let second = plan(Method::Overdamped2, Solver::Krylov);
    assert_eq!(pick(&second, &s, 64 * GIB), FreeChoice::Fast);
    assert_eq!(choose(&second, &s, 1e-4, GIB).unwrap().0, FreeChoice::Fast);
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

/// The table `bench/free_fit.py` records its fit over every shape in.
const FIT: &str =
    "free-space cost model constants (seconds a call per term), fitted to the rows of every shape";

/// The constants in the code are the last recorded fit over every shape
/// (`bench/results/free_cost.csv`).
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
        // The fit over every shape (`bench/free_fit.py`), not an example run's own.
        if row[5].starts_with(FIT) {
            recorded.insert(row[7].clone(), row[8].parse::<f64>().unwrap());
        }
    }
    for (name, v) in code {
        assert_eq!(recorded.get(name), Some(&v), "{name}");
    }
}

/// The measured table of `examples/free_cost.rs` (fast products in the steady state).
const MEASURED: &str = "free-space product paths, unit spheres, f64, one thread, CPU seconds a call (best of two; fast products with the kernel's transform kept)";
/// The storage past which the example times no path (its `MAX_BYTES`).
const MEASURED_BYTES: usize = 400_000_000;

/// The helical chain of `examples/shared/free_shapes.rs` (0.6 rad a bead, rising 0.8,
/// bonds 3): its centres.
fn helix_centres(n: usize) -> Vec<[f64; 3]> {
    // Bead `k` is a bond of 3 along (cos 0.6 k, sin 0.6 k, 0.8) past bead `k - 1`.
    let bond = |k: usize| {
        let d = [(0.6 * k as f64).cos(), (0.6 * k as f64).sin(), 0.8];
        let l = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        d.map(|x| 3.0 * x / l)
    };
    let beads = (1..n).scan([0.0f64; 3], |at, k| {
        let b = bond(k);
        *at = [at[0] + b[0], at[1] + b[1], at[2] + b[2]];
        Some(*at)
    });
    std::iter::once([0.0; 3]).chain(beads).take(n).collect()
}

/// The helical chain of `examples/shared/free_shapes.rs`: its bounding box.
pub(super) fn helix(n: usize) -> Spheres {
    let (mut lo, mut hi) = ([0.0f64; 3], [0.0f64; 3]);
    for p in helix_centres(n) {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    Spheres {
        n,
        bonds: 0,
        extent: [0, 1, 2].map(|c| hi[c] - lo[c]),
        a_max: 1.0,
        rpy: true,
    }
}

/// The model weighs the fast path wherever the kernel runs it, with the kernel's own
/// storage, and nowhere else: on the helical chain from 3,000 beads (measured: a
/// Brownian step of 2.3 s at 3,000 and 3.4 s at 10^4) the rule's grid along the chain
/// passes its bound, and a step widens the spreading until a grid fits
/// (`integrate::fast_parameters`); so does the model, and its storage fits the run's
/// limit. At 10^5 beads (a chain 190,000 radii long) no widening fits, and both refuse.
#[test]
fn the_fast_path_is_weighed_where_the_kernel_runs_it() {
    use hydrorattle::Real;
    for (n, runs) in [(3000, true), (10_000, true), (100_000, false)] {
        let pos: Vec<_> = helix_centres(n).into_iter().map(f64::v3_from).collect();
        let mut kp = hydrorattle::Params::<f64>::new(1e-3);
        kp.method = Method::Overdamped;
        kp.matrix_free = true;
        kp.pse = Some(1e-4);
        let kernel = hydrorattle::integrate::fast_storage(&kp, &pos, &vec![1.0; n]);
        assert_eq!(kernel.is_ok(), runs, "chain of {n}: {kernel:?}");
        let s = helix(n);
        assert_eq!(FreeCost::of(&s, 1e-4).fast.is_some(), runs, "chain of {n}");
        let p = overdamped();
        let fast = storage(&p, &s, 1e-4, FreeChoice::Fast);
        let pairs = storage(&p, &s, 1e-4, FreeChoice::MatrixFree).unwrap();
        let grid = kernel
            .ok()
            .flatten()
            .map(|z| 16 * z.complex + 8 * z.reals + 8 * z.index);
        assert_eq!(fast, grid.map(|g| pairs + g), "chain of {n}");
        assert!(
            fast.is_none_or(|b| b <= sizing::DEFAULT_LIMIT),
            "chain of {n}"
        );
    }
}

/// The model's choice against every measured row of `bench/results/free_cost.csv`
/// (`examples/free_cost.rs`: every shape, N = 10 to 1e4, and the cloud at 0.1 to 1e5,
/// CPU seconds a call): for each
/// shape and count, a step of one product and a step with a constraint solve, without
/// and with rotation, the path the model picks costs, as measured, at most a fifth more
/// than the measured fastest of the paths the step can run (as the kernel says, not the
/// model) within the storage the example times. A step's measured time is composed from the
/// measured calls as the model composes its own: the assembly and the products (the
/// solve's count from the box's record), and with rotation the pair paths' spin pass
/// or the fast path's grand product. The times are the record's, not the model's
/// constants: the test fails where the model's form or constants pick the wrong path.
#[test]
fn the_choice_matches_the_measured_rows() {
    use super::box_cost::PRODUCTS_SOLVE;
    let rows = numbers(MEASURED);
    let mut picks = Picks::default();
    for (shape, phi) in SHAPES {
        for n in [
            10, 30, 100, 300, 1000, 3000, 10_000, 20_000, 50_000, 100_000,
        ] {
            let case = format!("{shape}, N = {n}");
            let t = |q: &str| rows.get(&(case.clone(), q.to_string())).copied();
            let s0 = phi.map_or_else(|| helix(n), |phi| cloud(n, phi));
            for rotation in [false, true] {
                for bonds in [0, 1] {
                    let solve = if bonds > 0 { PRODUCTS_SOLVE } else { 0.0 };
                    let k = 1.0 + solve;
                    let spin = if rotation { t("spin pass") } else { Some(0.0) };
                    let pair = |asm: Option<f64>, rest: Option<f64>| Some(asm? + rest? + spin?);
                    let dense = pair(t("dense assembly"), t("dense product").map(|p| k * p));
                    let compact = t("compact copy")
                        .zip(t("compact product"))
                        .and_then(|(c, p)| {
                            pair(
                                t("dense assembly"),
                                Some(c + t("dense product")? + solve * p),
                            )
                        });
                    let free = pair(Some(0.0), t("matrix-free product").map(|p| k * p));
                    let fast = match rotation {
                        false => t("fast product 1e-4").map(|p| k * p),
                        true => t("fast grand-parameter product 1e-4")
                            .zip(t("fast grand product 1e-4"))
                            .map(|(p, g)| k * p + g),
                    };
                    let mut p = overdamped();
                    p.rotation = rotation;
                    let s = Spheres { bonds, ..s0 };
                    // What the step can run is the kernel's, not the model's: an
                    // overdamped Krylov step of RPY spheres in free space runs every
                    // path, the compact copy where the kernel keeps it.
                    let compact_kept = {
                        let mut pc = p;
                        pc.compact_products = true;
                        pc.params(n).compact_copy(n, bonds)
                    };
                    let runs = |c: FreeChoice| {
                        (c != FreeChoice::Compact || compact_kept)
                            && storage(&p, &s, 1e-4, c).is_some_and(|b| b <= MEASURED_BYTES)
                    };
                    let measured: Vec<(FreeChoice, f64)> = CHOICES
                        .into_iter()
                        .zip([dense, compact, free, fast])
                        .filter_map(|(c, m)| m.filter(|_| runs(c)).map(|m| (c, m)))
                        .collect();
                    if measured.len() < 2 {
                        continue;
                    }
                    let pick = choose(&p, &s, 1e-4, MEASURED_BYTES).unwrap().0;
                    let label = format!("{case}, rotation {rotation}, bonds {bonds}");
                    picks.check(&label, pick, &measured);
                }
            }
        }
    }
    picks.assert_all(100);
}

/// [`csv_fields`](crate::output::csv_fields) undoes
/// [`csv_field`](crate::output::csv_field).
#[test]
fn csv_fields_read_what_csv_field_writes() {
    let cells = ["plain", "a, b", "say \"hi\"", "", "x\"y,z"];
    let line: Vec<String> = cells.iter().map(|c| crate::output::csv_field(c)).collect();
    assert_eq!(crate::output::csv_fields(&line.join(",")), cells);
}
