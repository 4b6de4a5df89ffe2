//! `[free_space] method = "fast"`: the kernel parameters it sets (`Params::pse` without
//! a box, matrix-free), its storage sized without the mobility (a cloud of 10^5
//! spheres is not refused as dense, as `"dense"` is), each refusal at its line, the
//! write-back, rotation's spins against the dense path's, and a run of the shipped small cloud whose first step moves the cloud at
//! about the continuum speed.

use hydrorattle_host::scene::{FreeMethod, Scene, params};
use hydrorattle_host::sim::Engine;
use hydrorattle_host::sizing::{DEFAULT_LIMIT, Plan};

const SMALL: &str = include_str!("../../scenes/cloud_small.toml");
const CLOUD: &str = include_str!("../../scenes/cloud.toml");

fn scene(extra: &str, free: &str) -> String {
    format!(
        "[cloud]\ncount = 200\ncloud_radius = 20.0\n[integrator]\nmethod = \"overdamped\"\n\
         dt = 0.1\nduration = 0.2\n[free_space]\n{free}\n{extra}"
    )
}

#[test]
fn fast_sets_the_kernels_fast_product_and_writes_back() {
    let s = Scene::parse(&scene("", "method = \"fast\"\ntolerance = 1e-5"), "c.toml").unwrap();
    let f = s.free_space.unwrap();
    assert_eq!((f.method, f.tolerance), (FreeMethod::Fast, 1e-5));
    assert!(s.integrator.matrix_free, "the run is matrix-free");
    let p = params::<f64>(&s);
    assert_eq!(p.pse, Some(1e-5));
    assert!(p.matrix_free && p.periodic.is_none() && p.wall.is_none());
    let again = Scene::parse(&s.to_toml(), "written.toml").unwrap();
    assert_eq!(again, s);
    // "dense" is the path that was there before: no fast product.
    let d = Scene::parse(&scene("", "method = \"dense\""), "c.toml").unwrap();
    assert_eq!(params::<f64>(&d).pse, None);
    assert!(!d.integrator.matrix_free);
}

#[test]
fn a_cloud_of_a_hundred_thousand_spheres_is_sized_as_products() {
    // The count alone sizes the storage: checked before any sphere is placed.
    let big = |method: &str| {
        let text = format!(
            "[cloud]\ncount = 100000\ncloud_radius = 230.0\n[integrator]\nmethod = \"overdamped\"\n\
             dt = 0.1\nduration = 0.1\n[free_space]\nmethod = \"{method}\"\n"
        );
        Scene::parse(&text, "big.toml")
    };
    let e = big("dense").unwrap_err();
    assert_eq!(e.line(), Some(2), "{}", e.message);
    assert!(e.too_large.is_some(), "{}", e.message);
    let s = big("fast").unwrap();
    let bytes = Plan::of(&s).bytes(100_000, 0).unwrap();
    // O(N): a few hundred bytes a sphere, not 48 N^2 / 2 (240 GB).
    assert!(bytes < 1000 * 100_000, "{bytes} bytes");
    assert!(bytes < DEFAULT_LIMIT);
}

#[test]
fn what_fast_cannot_run_is_refused_at_its_line() {
    let at = |extra: &str, free: &str| {
        let e = Scene::parse(&scene(extra, free), "c.toml").unwrap_err();
        (e.line(), e.message)
    };
    let fast = "method = \"fast\"";
    for (extra, says) in [
        ("[wall]\nheight = -30.0", "wall"),
        ("[model]\nhydrodynamics = \"oseen\"", "rpy"),
        ("[model]\nlevel = \"auto\"", "manual"),
        (
            "[brownian]\ntemperature = 1.0\nsqrt = \"cholesky\"",
            "cholesky",
        ),
    ] {
        let (line, m) = at(extra, fast);
        assert_eq!(line, Some(9), "{extra}: {m}");
        assert!(m.contains(says), "{extra}: {m}");
    }
    let (line, m) = at("", "method = \"fast\"\ntolerance = 1.0");
    assert_eq!(line, Some(10), "{m}");
    assert!(m.contains("between"), "{m}");
    let (line, m) = at("[box]\nsize = [50.0, 50.0, 50.0]", fast);
    assert_eq!(line, Some(8), "{m}");
    assert!(m.contains("[box]"), "{m}");
    let (line, m) = at("", "method = \"quick\"");
    assert_eq!(line, Some(9), "{m}");
}

/// `rotation = true` runs on the fast product: the spins after a step within the
/// tolerance of the same scene's on the dense path (`"dense"`).
#[test]
fn fast_runs_rotation_with_the_dense_spins() {
    let rotating = |free: &str| {
        let s = Scene::parse(&scene("[model]\nrotation = true", free), "c.toml").unwrap();
        let mut e = Engine::<f64>::new(&s, DEFAULT_LIMIT).unwrap();
        e.step().unwrap();
        (params::<f64>(&s), e.beads.omega.clone())
    };
    let (pf, fast) = rotating("method = \"fast\"\ntolerance = 1e-6");
    assert!(pf.rotation && pf.pse == Some(1e-6) && pf.matrix_free);
    let (pd, dense) = rotating("method = \"dense\"");
    assert!(pd.rotation && pd.pse.is_none());
    let big = dense.iter().map(|w| w.length()).fold(0.0, f64::max);
    let err = fast
        .iter()
        .zip(&dense)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max)
        / big;
    assert!(big > 0.0 && err < 1e-6 && err > 0.0, "{err}");
}

/// `[near_field]` runs on the fast product (the far field of its iterative product): a
/// step's velocities within the tolerance of the same scene's on the dense path.
#[test]
fn fast_runs_the_near_field_with_the_dense_velocities() {
    let near = "[near_field]";
    let run = |free: &str| {
        let text = format!(
            "[cloud]\ncount = 60\ncloud_radius = 6.0\n[integrator]\nmethod = \"overdamped\"\n\
             dt = 0.01\nduration = 0.02\n[free_space]\n{free}\n{near}"
        );
        let s = Scene::parse(&text, "c.toml").unwrap();
        let mut e = Engine::<f64>::new(&s, DEFAULT_LIMIT).unwrap();
        let before = s.positions();
        e.step().unwrap();
        let v: Vec<[f64; 3]> = (0..before.len())
            .map(|k| std::array::from_fn(|c| e.beads.pos[k][c] - before[k][c]))
            .collect();
        (params::<f64>(&s), v)
    };
    let (pf, fast) = run("method = \"fast\"\ntolerance = 1e-6");
    assert!(pf.near.is_some() && pf.pse == Some(1e-6) && pf.matrix_free);
    let (pd, dense) = run("method = \"dense\"");
    assert!(pd.near.is_some() && pd.pse.is_none());
    let len = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let big = dense.iter().map(len).fold(0.0, f64::max);
    let err = fast
        .iter()
        .zip(&dense)
        .map(|(a, b)| len(&std::array::from_fn(|c| a[c] - b[c])))
        .fold(0.0, f64::max)
        / big;
    assert!(big > 0.0 && err < 1e-5 && err > 0.0, "{err}");
}

#[test]
fn the_shipped_clouds_read_and_the_small_one_falls_at_the_continuum_speed() {
    let big = Scene::parse(CLOUD, "cloud.toml").unwrap();
    assert_eq!(big.particles.len(), 10_000);
    let s = Scene::parse(SMALL, "cloud_small.toml").unwrap();
    let n = s.particles.len();
    let mut e = Engine::<f64>::new(&s, DEFAULT_LIMIT).unwrap();
    let before: Vec<[f64; 3]> = s.positions();
    e.step().unwrap();
    let dt = s.integrator.dt;
    let mean = (0..n)
        .map(|k| (before[k][2] - e.beads.pos[k][2]) / dt)
        .sum::<f64>()
        / n as f64;
    // U0 = 1 (density 4.5, gravity 1); the centres fill a ball of radius R - 1. One
    // seed scatters by 2 (0.1195) (6/5) sqrt(N) a / R_c U0 (falling_cloud.rs); the
    // finite-N correction (-6 phi) is 0.06.
    let rc = s.cloud.unwrap().cloud_radius - 1.0;
    let expected = 1.0 + 1.2 * (n - 1) as f64 / rc - 6.0 * n as f64 / rc.powi(3);
    let sigma = 2.0 * 0.1195 * 1.2 * (n as f64).sqrt() / rc;
    assert!(
        (mean - expected).abs() < 4.0 * sigma,
        "{mean} against {expected} +- {sigma}"
    );
}

/// `method = "overdamped2"` runs on the fast product (the predictor's and the
/// corrector's products): matrix-free, and two steps within the tolerance of the same
/// scene's on the dense path.
#[test]
fn fast_runs_overdamped2_as_the_dense_path() {
    let second = |free: &str| {
        let text = scene("", free).replace("\"overdamped\"", "\"overdamped2\"");
        let s = Scene::parse(&text, "c.toml").unwrap();
        let mut e = Engine::<f64>::new(&s, DEFAULT_LIMIT).unwrap();
        e.step().unwrap();
        e.step().unwrap();
        (s, e.beads.pos.clone())
    };
    let (sf, fast) = second("method = \"fast\"\ntolerance = 1e-6");
    assert!(sf.integrator.matrix_free && params::<f64>(&sf).pse == Some(1e-6));
    assert_eq!(params::<f64>(&sf).method, hydrorattle::Method::Overdamped2);
    let (sd, dense) = second("method = \"dense\"");
    let start = sd.positions();
    let moved = dense
        .iter()
        .zip(&start)
        .map(|(a, b)| (*a - <f64 as hydrorattle::Real>::v3_from(*b)).length())
        .fold(0.0, f64::max);
    let err = fast
        .iter()
        .zip(&dense)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max)
        / moved;
    assert!(moved > 0.0 && err < 3e-6 && err > 0.0, "{err}");
}
