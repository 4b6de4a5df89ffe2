//! The grand mobility against `tests/data/rpy_grand_mobility.json`, produced by an
//! independent implementation (pygrpy; provenance in `tests/data/README.md`). Ordering there: all translations, then all
//! rotations, particle-major then x, y, z — the same as `assemble_grand`'s blocks.

use hydrorattle::linalg::{sym_get, tri};
use hydrorattle::mobility::{Hydro, assemble_grand};
use hydrorattle::{Real, particles::check_pairs};

struct Case {
    name: String,
    eta: f64,
    radii: Vec<f64>,
    centres: Vec<[f64; 3]>,
    mu: Vec<Vec<f64>>,
}

fn load() -> Vec<Case> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/rpy_grand_mobility.json"
    );
    let text = std::fs::read_to_string(path).expect("tests/data/rpy_grand_mobility.json");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let arr = |x: &serde_json::Value| -> Vec<f64> {
        x.as_array()
            .unwrap()
            .iter()
            .map(|y| y.as_f64().unwrap())
            .collect()
    };
    v["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| Case {
            name: c["name"].as_str().unwrap().to_string(),
            eta: c["viscosity"].as_f64().unwrap(),
            radii: arr(&c["radii"]),
            centres: c["centres"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| {
                    let a = arr(p);
                    [a[0], a[1], a[2]]
                })
                .collect(),
            mu: c["grand_mobility"]
                .as_array()
                .unwrap()
                .iter()
                .map(arr)
                .collect(),
        })
        .collect()
}

/// Largest entry error relative to the largest entry of the reference matrix.
fn max_rel_error<T: Real>(c: &Case) -> f64 {
    let n = c.radii.len();
    let pos: Vec<T::V3> = c.centres.iter().map(|p| T::v3_from(*p)).collect();
    let rad: Vec<T> = c.radii.iter().map(|&a| T::from_f64(a)).collect();
    let mut out = vec![T::M3_ZERO; tri(2 * n)];
    assemble_grand(Hydro::Rpy, T::from_f64(c.eta), &pos, &rad, &mut out).unwrap();
    let scale = c.mu.iter().flatten().fold(0.0f64, |a, &b| a.max(b.abs()));
    let mut err = 0.0f64;
    for (r, row) in c.mu.iter().enumerate() {
        for (col, &want) in row.iter().enumerate() {
            let got = T::m3_get(sym_get::<T>(&out, r / 3, col / 3), r % 3, col % 3).to_f64();
            err = err.max((got - want).abs() / scale);
        }
    }
    err
}

macro_rules! reference_tests {
    ($name:ident, $t:ty, $tol:expr) => {
        #[test]
        fn $name() {
            let cases = load();
            assert!(cases.len() >= 5);
            for c in &cases {
                let e = max_rel_error::<$t>(c);
                eprintln!("{} {}: max relative error {e:.3e}", stringify!($t), c.name);
                assert!(e <= $tol, "{}: error {e:e} > {}", c.name, $tol);
            }
        }
    };
}

reference_tests!(grand_mobility_matches_reference_f64, f64, 1e-12);
reference_tests!(grand_mobility_matches_reference_f32, f32, 1e-5);

#[test]
fn reference_covers_the_overlapping_branch() {
    let cases = load();
    let overlapping = cases.iter().any(|c| {
        let pos: Vec<_> = c.centres.iter().map(|p| f64::v3_from(*p)).collect();
        check_pairs::<f64>(&pos, &c.radii, false).is_err()
    });
    assert!(
        overlapping,
        "the reference must exercise the overlapping RPY branch"
    );
}
