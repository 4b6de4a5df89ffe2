//! Tests of the box's cost model and of the PSE sizing: the choice on the cases where it
//! was measured, its constants against their record, and PSE scenes sized as PSE runs
//! them (refused at the `[box]` table, naming the grid, where the grid is too large).

use super::box_cost::*;
use super::*;

/// `auto` on the cases the model was asked about: measured (`bench/results/auto_box.csv`
/// and the runs that found the choice wrong), Ewald is far faster for a lone sphere in a
/// box of 50 (0.04 ms against 119-144 ms a product), for the shipped 13-bead periodic
/// chain (15-18 times) and a 6-bead chain (4 against 1438 steps/s), and for two spheres
/// in a box of 1000 (PSE's grid would be 328 GiB); PSE for suspensions at volume
/// fraction 0.1 from a hundred spheres on (16 to 41 times at N = 400, `docs/PERIODIC.md`).
/// The test compares the model's choice, not timings.
#[test]
fn auto_picks_the_measured_faster_path() {
    let cube = |l: f64| [l; 3];
    let phi = |n: usize, a: f64| {
        cube((n as f64 * 4.0 / 3.0 * std::f64::consts::PI * a.powi(3) / 0.1).cbrt())
    };
    let ewald = [
        (cube(50.0), 1, 1.0, 1e-6),
        (cube(50.0), 1, 1.0, 1e-3),
        (cube(1000.0), 2, 1.0, 1e-6),
        (cube(200.0), 2, 1.0, 1e-12),
    ];
    for (size, n, a, tol) in ewald {
        let c = BoxCost::of(size, n, a, tol);
        assert!(!c.pse_pays(), "{size:?} N {n} tol {tol:e}: {c:?}");
    }
    for (n, tol) in [
        (100, 1e-6),
        (400, 1e-4),
        (1000, 1e-6),
        (20_000, 1e-6),
        (100_000, 1e-3),
    ] {
        let c = BoxCost::of(phi(n, 1.0), n, 1.0, tol);
        assert!(c.pse_pays(), "N {n} at 0.1, tol {tol:e}: {c:?}");
    }
    // PSE refuses a sphere of a third of the edge: the Ewald sum, whatever the count.
    assert_eq!(BoxCost::of(cube(10.0), 3, 4.5, 1e-6).pse, None);
}

/// The constants in the code are the ones the measurement fitted, as recorded with its
/// commit, machine and command.
#[test]
fn the_constants_are_the_recorded_fit() {
    let csv = include_str!("../../../bench/results/auto_box.csv");
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (kind, name, value) = (col("kind"), col("constant"), col("value"));
    let code = [
        ("EWALD_FIXED", EWALD_FIXED),
        ("EWALD_SPHERE", EWALD_SPHERE),
        ("EWALD_PAIR", EWALD_PAIR),
        ("PSE_FIXED", PSE_FIXED),
        ("PSE_GRID", PSE_GRID),
        ("PSE_NEAR", PSE_NEAR),
        ("PSE_SPREAD", PSE_SPREAD),
    ];
    let mut seen = 0;
    for row in lines.map(|l| l.split(',').collect::<Vec<_>>()) {
        assert_eq!(row.len(), head.len(), "{row:?}");
        assert!(!row[col("commit")].is_empty() && !row[col("command")].is_empty());
        if row[kind] == "constant" {
            let (_, v) = code.iter().find(|(n, _)| *n == row[name]).unwrap();
            assert_eq!(row[value].parse::<f64>().ok(), Some(*v), "{}", row[name]);
            seen += 1;
        }
    }
    assert_eq!(seen, code.len());
}

fn suspension(count: usize, method: &str, extra: &str) -> String {
    format!(
        "[suspension]\ncount = {count}\nfraction = 0.1\n\n[box]\nmethod = \"{method}\"\n{extra}\n\
         [integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 0.01\n"
    )
}

/// A PSE suspension is sized as PSE runs it (grid, near-field lists and `O(N)`
/// vectors): 20,000 spheres pass the default 8 GiB limit (they were refused as 8.9 GiB,
/// sized as a stored `N x N` mobility), and the estimate at N = 10^5 is under 1 GiB,
/// deterministic and Brownian (it was 224 and 559 GiB).
#[test]
fn pse_is_sized_without_the_dense_mobility() {
    let s = Scene::parse(&suspension(20_000, "auto", ""), "s.toml").unwrap();
    assert_eq!(s.particles.len(), 20_000);
    let run = s.with_box_resolved();
    assert_eq!(run.periodic.map(|b| b.method), Some(BoxMethod::Pse));
    let thermal = Thermal {
        temperature: 1.0,
        seed: 1,
        drift: Default::default(),
        sqrt: Default::default(),
    };
    for brownian in [None, Some(thermal)] {
        let mut plan = sizing::Plan::of(&run);
        plan.brownian = brownian;
        let bytes = plan.bytes(100_000, 0).unwrap();
        eprintln!("N = 1e5, {brownian:?}: {}", sizing::human(bytes as u64));
        assert!(
            bytes < 1 << 30,
            "{brownian:?}: {}",
            sizing::human(bytes as u64)
        );
    }
}

/// Two spheres in a box of 1000: `"pse"` is refused at the `[box]` method's line, naming
/// the grid and the box (not the beads); `"auto"` runs them on the Ewald sum.
#[test]
fn a_grid_too_large_is_refused_at_the_box_naming_the_grid() {
    let text = |m: &str| {
        format!(
            "[[particle]]\nposition = [0, 0, 0]\nradius = 1\n\n\
             [[particle]]\nposition = [5, 0, 0]\nradius = 1\n\n\
             [box]\nsize = [1000, 1000, 1000]\nmethod = \"{m}\"\n\n\
             [integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 0.01\n"
        )
    };
    let e = Scene::parse(&text("pse"), "b.toml").unwrap_err();
    assert_eq!(e.location.map(|l| l.0), Some(11), "{e}");
    assert!(
        e.message.contains("PSE grid") && e.message.contains("too large for the tolerance"),
        "{e}"
    );
    assert!(!e.message.contains("fewer beads"), "{e}");
    let s = Scene::parse(&text("auto"), "b.toml")
        .unwrap()
        .with_box_resolved();
    assert_eq!(s.periodic.map(|b| b.method), Some(BoxMethod::Ewald));
    // A grid edge past the kernel's bound at a fine tolerance: refused the same way.
    let fine = text("pse").replace("method = \"pse\"", "method = \"pse\"\ntolerance = 1e-12");
    let e = Scene::parse(&fine, "b.toml").unwrap_err();
    assert_eq!(e.location.map(|l| l.0), Some(11), "{e}");
    assert!(e.message.contains("grid"), "{e}");
}

/// A sphere of a third of the edge or more: `"pse"` is refused at its line (PSE misses
/// its tolerance there), `"auto"` takes the Ewald sum. An `f32` box with a tolerance
/// below what PSE reaches in `f32` is refused at the tolerance.
#[test]
fn pse_refuses_what_it_cannot_meet() {
    let big = |m: &str| {
        format!(
            "[[particle]]\nposition = [0, 0, 0]\nradius = 4.5\n\n\
             [box]\nsize = [10, 10, 10]\nmethod = \"{m}\"\n\n\
             [integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 0.01\n"
        )
    };
    let e = Scene::parse(&big("pse"), "b.toml").unwrap_err();
    assert_eq!(e.location.map(|l| l.0), Some(7), "{e}");
    assert!(e.message.contains("third of the box"), "{e}");
    let s = Scene::parse(&big("auto"), "b.toml")
        .unwrap()
        .with_box_resolved();
    assert_eq!(s.periodic.map(|b| b.method), Some(BoxMethod::Ewald));
    for m in ["pse", "auto"] {
        let text = suspension(200, m, "tolerance = 1e-8\n").replace(
            "duration = 0.01\n",
            "duration = 0.01\nprecision = \"f32\"\n",
        );
        let e = Scene::parse(&text, "s.toml").unwrap_err();
        assert_eq!(e.location.map(|l| l.0), Some(7), "{m}: {e}");
        assert!(e.message.contains("f32"), "{e}");
        let fine = text.replace("tolerance = 1e-8", "tolerance = 1e-5");
        assert!(Scene::parse(&fine, "s.toml").is_ok(), "{m}");
    }
}

/// The shipped 13-bead periodic chain (bonds, Brownian noise, midpoint) and a 6-bead one
/// under `method = "auto"`: the Ewald sum (measured 15 to 18 times and 360 times faster
/// a step: PSE pays some 80 products a step where Ewald assembles twice), and so does
/// the shipped suspension (32 spheres, hard contacts: measured 69 steps/s on Ewald
/// against 31 on PSE, `host-demo run` of it with each method).
#[test]
fn auto_takes_ewald_for_the_shipped_chains() {
    let scene = |name: &str| {
        let path = format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        std::fs::read_to_string(path).unwrap()
    };
    let chain = scene("periodic_chain").replace("method = \"ewald\"", "method = \"auto\"");
    for tails in ["tails = 12", "tails = 5"] {
        let text = chain.replace("tails = 12", tails);
        let s = Scene::parse(&text, "c.toml").unwrap().with_box_resolved();
        assert_eq!(
            s.periodic.map(|b| b.method),
            Some(BoxMethod::Ewald),
            "{tails}"
        );
    }
    let s = Scene::parse(&scene("periodic_suspension"), "s.toml").unwrap();
    let s = s.with_box_resolved();
    assert_eq!(s.periodic.map(|b| b.method), Some(BoxMethod::Ewald));
}
