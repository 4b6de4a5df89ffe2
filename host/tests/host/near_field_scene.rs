//! `[near_field]` in scene files: parsed with its defaults, written back in `scene.toml`
//! to the same scene, handed to the kernel as `Params::near`, refused at its line where
//! the near field does not run, and run: two spheres at `s = 2.1` fall along their line
//! of centres at Stimson and Jeffery's speed (1.5363 `U0`, the exact series; RPY alone
//! gives 1.6063).

use hydrorattle_host::scene::{NearField, Scene, params};
use hydrorattle_host::sim::{RunOptions, run};

/// Two unit spheres of unit buoyant weight, centres 2.1 apart along `z`, with `near`
/// (a table's text, or nothing) and `extra` keys in `[model]` and `[integrator]`.
fn scene(near: &str, hydro: &str, method: &str) -> String {
    let rho = 3.0 / (4.0 * std::f64::consts::PI);
    format!(
        "[[particle]]\nposition = [0.0, 0.0, -1.05]\nradius = 1.0\ndensity = {rho}\n\n\
         [[particle]]\nposition = [0.0, 0.0, 1.05]\nradius = 1.0\ndensity = {rho}\n\n\
         [model]\nhydrodynamics = \"{hydro}\"\n\n\
         [integrator]\nmethod = \"{method}\"\ndt = 0.01\nduration = 0.05\n\n\
         {near}"
    )
}

#[test]
fn the_table_reads_writes_back_and_sets_the_kernel() {
    let s = Scene::parse(&scene("[near_field]\n", "rpy", "overdamped"), "n.toml").unwrap();
    assert_eq!(s.near_field, Some(NearField::default()));
    let d = hydrorattle::stokesian::NearField::<f64>::default();
    assert_eq!(params::<f64>(&s).near, Some(d));
    let text = s.to_toml();
    assert!(text.contains("[near_field]"), "{text}");
    assert_eq!(Scene::parse(&text, "scene.toml").unwrap(), s);
    let keys = "[near_field]\ncutoff = 2.0\nwall_cutoff = 1.0\nmin_gap = 0.01\n";
    let s = Scene::parse(&scene(keys, "rpy", "overdamped2"), "n.toml").unwrap();
    let want = NearField {
        cutoff: 2.0,
        wall_cutoff: 1.0,
        min_gap: 0.01,
    };
    assert_eq!(s.near_field, Some(want));
    assert_eq!(params::<f32>(&s).near.map(|n| n.min_gap), Some(0.01));
    // Without the table: no near field, and the scene's JSON has no key for it.
    let plain = Scene::parse(&scene("", "rpy", "overdamped"), "plain").unwrap();
    assert_eq!(plain.near_field, None);
    assert_eq!(params::<f64>(&plain).near, None);
    let json = serde_json::to_string(&plain).unwrap();
    assert!(!json.contains("near_field"), "{json}");
}

#[test]
fn refused_at_the_line_of_the_table_or_the_key() {
    let cases = [
        (
            "[near_field]\nmin_gap = 0.0\n",
            "rpy",
            "overdamped",
            "min_gap",
            20,
        ),
        (
            "[near_field]\ncutoff = -1.0\n",
            "rpy",
            "overdamped",
            "cutoff",
            20,
        ),
        ("[near_field]\n", "oseen", "overdamped", "rpy", 19),
        ("[near_field]\n", "rpy", "rattle", "near field", 19),
        ("[near_field]\nfoo = 1\n", "rpy", "overdamped", "foo", 20),
    ];
    for (near, hydro, method, says, line) in cases {
        let e = Scene::parse(&scene(near, hydro, method), "bad.toml").unwrap_err();
        assert!(
            e.message.contains(says),
            "{near} {hydro} {method}: {}",
            e.message
        );
        assert_eq!(
            e.line(),
            Some(line),
            "{near} {hydro} {method}: {}",
            e.message
        );
    }
}

#[test]
fn two_spheres_fall_at_stimson_and_jeffery_speed() {
    // Stimson and Jeffery's exact U / U0 at s = 2.1 (docs/NEAR.md), U0 = 1 / (6 pi).
    let (exact, rpy) = (1.53633, 1.6063);
    let u0 = 1.0 / (6.0 * std::f64::consts::PI);
    for (near, want) in [("[near_field]\n", exact), ("", rpy)] {
        let s = Scene::parse(&scene(near, "rpy", "overdamped"), "fall").unwrap();
        let r = run(&s, "fall", None, RunOptions::default()).unwrap();
        assert_eq!(r.summary.failure, None);
        // The pair translates rigidly (equal spheres): five steps of 0.01.
        let t = r.last.time - r.initial.time;
        for (a, b) in r.initial.positions.iter().zip(&r.last.positions) {
            let u = (a[2] - b[2]) / t / u0;
            assert!((u / want - 1.0).abs() < 2e-3, "{near:?}: {u} vs {want}");
        }
    }
}

#[test]
fn matrix_free_runs_the_iterative_near_field_at_stimson_and_jeffery_speed() {
    // `matrix_free` with `[near_field]` takes the kernel's iterative Stokesian dynamics
    // product: the same exact speed as the dense path, without the dense matrix.
    let exact = 1.53633;
    let u0 = 1.0 / (6.0 * std::f64::consts::PI);
    let text = scene("[near_field]\n", "rpy", "overdamped")
        .replace("duration = 0.05\n", "duration = 0.05\nmatrix_free = true\n");
    let s = Scene::parse(&text, "fall").unwrap();
    assert!(s.integrator.matrix_free);
    let r = run(&s, "fall", None, RunOptions::default()).unwrap();
    assert_eq!(r.summary.failure, None);
    let t = r.last.time - r.initial.time;
    for (a, b) in r.initial.positions.iter().zip(&r.last.positions) {
        let u = (a[2] - b[2]) / t / u0;
        assert!((u / exact - 1.0).abs() < 2e-3, "{u} vs {exact}");
    }
}
