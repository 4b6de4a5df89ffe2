//! `[brownian]` scene keys: parsed with their defaults, and a run is fixed by
//! its seed (same seed same bits in f32 and f64; another seed another run; `kT = 0` the
//! deterministic run).

use crate::common::ok;
use hydrorattle_host::scene::{Drift, Precision, Scene, Sqrt, Thermal};
use hydrorattle_host::sim::{RunOptions, run};

const SHIPPED: &str = include_str!("../../../host/scenes/brownian_chain.toml");

/// The shipped Brownian scene with its `[brownian]` table replaced by `table` (none
/// when empty) and the given precision.
fn scene(table: &str, precision: &str) -> Scene {
    let body = SHIPPED.split("[brownian]").next().unwrap();
    let body = body.replace(
        "precision = \"f64\"",
        &format!("precision = \"{precision}\""),
    );
    Scene::parse(&format!("{body}{table}"), "test").unwrap()
}

fn last(scene: &Scene) -> Vec<[f64; 3]> {
    let opts = RunOptions {
        max_steps: Some(40),
        ..Default::default()
    };
    let r = run(scene, "test", None, opts).unwrap();
    assert_eq!(r.summary.failure, None);
    r.last.positions
}

#[test]
fn keys_and_defaults() {
    let s = Scene::parse(SHIPPED, "shipped").unwrap();
    assert_eq!(
        s.brownian,
        Some(Thermal {
            temperature: 0.5,
            seed: 7,
            drift: Drift::Midpoint,
            sqrt: Sqrt::Auto,
        })
    );
    let s = scene("[brownian]\ntemperature = 2.0\n", "f64");
    assert_eq!(
        s.brownian.map(|b| (b.seed, b.drift)),
        Some((1, Drift::Midpoint))
    );
    assert_eq!(scene("", "f64").brownian, None);
    assert_eq!(s.integrator.precision, Precision::F64);
}

#[test]
fn the_seed_fixes_the_run() {
    for precision in ["f32", "f64"] {
        let with = |seed: u64| {
            scene(
                &format!("[brownian]\ntemperature = 0.5\nseed = {seed}\n"),
                precision,
            )
        };
        let a = last(&with(7));
        assert_eq!(a, last(&with(7)), "{precision}: same seed, different runs");
        assert_ne!(a, last(&with(8)), "{precision}: another seed, same run");
        let cold = last(&scene(
            "[brownian]\ntemperature = 0.0\nseed = 7\n",
            precision,
        ));
        assert_eq!(
            cold,
            last(&scene("", precision)),
            "{precision}: kT = 0 is not deterministic"
        );
    }
}

/// The issue-19 star: every solver refuses its step 2557 (no root near the start);
/// the run retries it as two half steps along a Brownian bridge, counts the retry in
/// the summary and runs to the end. Without the retry the run stopped at step 2557.
#[test]
fn a_refused_step_is_retried_split_and_counted() {
    let text = include_str!("../data/star_kt1.toml");
    for solver in ["newton", "sweep", "krylov"] {
        let text = text.replace(
            "duration = 270.0",
            &format!("duration = 270.0\nsolver = \"{solver}\""),
        );
        let s = Scene::parse(&text, "star").unwrap();
        let r = run(&s, "star", None, RunOptions::default()).unwrap();
        assert_eq!(r.summary.failure, None, "{solver}");
        assert_eq!(r.summary.steps_done, 3000, "{solver}");
        assert_eq!(r.summary.retries.steps, 1, "{solver}");
        assert_eq!(r.summary.retries.substeps, 2, "{solver}");
        // The retried step ends at the unsplit step's time.
        let t = (0..3000).fold(0.0f64, |t, _| t + 0.09);
        assert_eq!(r.last.time, t, "{solver}");
    }
}

/// A Brownian run (the star at kT = 1, with its retried step before the checkpoint)
/// resumed from its checkpoint writes the same bytes as one run: the generator's state
/// is saved and restored.
#[test]
fn a_brownian_run_resumes_to_the_bytes_of_one_run() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("brownian-restart");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = include_str!("../data/star_kt1.toml");
    // To step 2700 (past the retried step 2557) in one run and in two.
    let long = dir.join("long.toml");
    std::fs::write(
        &long,
        text.replace("duration = 270.0", "duration = 243.0\n[output]\nevery = 50"),
    )
    .unwrap();
    let short = dir.join("short.toml");
    std::fs::write(
        &short,
        text.replace("duration = 270.0", "duration = 234.0\n[output]\nevery = 50"),
    )
    .unwrap();
    let (one, two) = run_and_resume(&dir, &long, &short, "117", "243");
    same_files(
        &one,
        &two,
        &["trajectory.xyz", "trajectory.gsd", "observables.csv"],
    );
    let json = |d: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap()
    };
    let (s1, s2) = (json(&one), json(&two));
    assert_eq!(s1["retries"]["steps"], 1);
    // Every kernel step that succeeded: the refused one's two halves instead of it.
    assert_eq!(s1["noise_iterations"]["steps"], 2701);
    for key in [
        "final_observables",
        "steps_done",
        "retries",
        "noise_iterations",
    ] {
        assert_eq!(s1[key], s2[key], "{key}");
    }
}

/// `summary.json` records the Lanczos iterations of a thermal run's noise per kernel
/// step (`noise_iterations`): counted with `sqrt = "lanczos"`, zero with the Cholesky
/// factor `auto` takes for the 25-bead chain, absent without a temperature.
#[test]
fn the_summary_records_the_noise_iterations() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("noise-iterations");
    let _ = std::fs::remove_dir_all(&dir);
    let summary = |table: &str, name: &str| -> serde_json::Value {
        let out = dir.join(name);
        let opts = RunOptions {
            max_steps: Some(40),
            ..Default::default()
        };
        let r = run(&scene(table, "f64"), name, Some(&out), opts).unwrap();
        assert_eq!(r.summary.failure, None, "{name}");
        let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    };
    let lanczos = summary(
        "[brownian]\ntemperature = 0.5\nsqrt = \"lanczos\"\n",
        "lanczos",
    );
    let n = &lanczos["noise_iterations"];
    assert_eq!(n["sqrt"], "lanczos", "{n}");
    assert_eq!(n["steps"], 40, "{n}");
    assert_eq!(n["cap"], 64, "{n}");
    assert_eq!(n["capped"], 0, "{n}");
    let (mean, max, total) = (
        n["mean"].as_f64().unwrap(),
        n["max"].as_u64().unwrap(),
        n["total"].as_u64().unwrap(),
    );
    assert!(mean > 1.0 && mean <= max as f64 && max < 64, "{n}");
    assert_eq!(mean, total as f64 / 40.0, "{n}");
    let cholesky = summary("[brownian]\ntemperature = 0.5\n", "cholesky");
    let n = &cholesky["noise_iterations"];
    assert_eq!(n["sqrt"], "cholesky (auto)", "{n}");
    assert_eq!(n["steps"], 40, "{n}");
    assert_eq!(
        (n["max"].as_u64(), n["total"].as_u64()),
        (Some(0), Some(0)),
        "{n}"
    );
    for (table, name) in [
        ("", "deterministic"),
        ("[brownian]\ntemperature = 0.0\n", "cold"),
    ] {
        let s = summary(table, name);
        assert!(s.get("noise_iterations").is_none(), "{name}: {s}");
    }
}

/// `sqrt` picks the kernel's square root of the mobility; a bad value is refused at
/// its file and line.
#[test]
fn sqrt_key() {
    let s = scene("[brownian]\ntemperature = 2.0\nsqrt = \"lanczos\"\n", "f64");
    assert_eq!(s.brownian.map(|b| b.sqrt), Some(Sqrt::Lanczos));
    let s = scene(
        "[brownian]\ntemperature = 2.0\nsqrt = \"cholesky\"\n",
        "f32",
    );
    assert_eq!(s.brownian.map(|b| b.sqrt), Some(Sqrt::Cholesky));
    // A written scene keeps the choice.
    let back = Scene::parse(&s.to_toml(), "written").unwrap();
    assert_eq!(back.brownian, s.brownian);
    // Both square roots run the shipped chain.
    for sqrt in ["cholesky", "lanczos"] {
        let table = format!("[brownian]\ntemperature = 0.5\nseed = 7\nsqrt = \"{sqrt}\"\n");
        assert_eq!(last(&scene(&table, "f64")).len(), 25);
    }
    let body = SHIPPED.split("[brownian]").next().unwrap();
    let text = format!("{body}[brownian]\ntemperature = 2.0\nsqrt = \"qr\"\n");
    let err = Scene::parse(&text, "bad.toml").unwrap_err();
    assert_eq!(err.line(), Some(text.lines().count()), "{err}");
    assert!(err.to_string().contains("qr"), "{err}");
}

/// The shipped FENE dumbbell: a spring of rest length 0 and the `fene` key reach the
/// kernel (a written scene keeps them), and the run samples `<Q^2> = 3 kT/H * b/(b+5)`
/// = 2 (b = 10) within 3 block standard errors (its 1e5 steps give about 4 %).
#[test]
fn fene_dumbbell_scene() {
    let text = include_str!("../../../host/scenes/fene_dumbbell.toml");
    let s = Scene::parse(text, "fene_dumbbell.toml").unwrap();
    assert_eq!(s.integrator.fene, Some(10f64.sqrt()));
    assert_eq!(s.bonds[0].length, 0.0);
    let back = Scene::parse(&s.to_toml(), "written").unwrap();
    assert_eq!(back.integrator, s.integrator);
    assert_eq!(back.bonds[0].length, 0.0);
    let out = std::env::temp_dir().join(format!("fene-scene-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let opts = RunOptions {
        progress: false,
        ..Default::default()
    };
    let r = run(&s, "fene", Some(&out), opts).unwrap();
    assert_eq!(r.summary.failure, None);
    // One frame every 500 steps (1 time unit, 2 relaxation times apart): nearly
    // independent samples; blocks of 10.
    let frames = hydrorattle_host::output::read_xyz_file(&out.join("trajectory.xyz")).unwrap();
    std::fs::remove_dir_all(&out).unwrap();
    let q2: Vec<f64> = frames[1..]
        .iter()
        .map(|f| {
            let (a, b) = (f.positions[0], f.positions[1]);
            (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>()
        })
        .collect();
    let blocks: Vec<f64> = q2
        .chunks_exact(10)
        .map(|c| c.iter().sum::<f64>() / 10.0)
        .collect();
    let k = blocks.len() as f64;
    let mean = blocks.iter().sum::<f64>() / k;
    let se = (blocks.iter().map(|b| (b - mean).powi(2)).sum::<f64>() / (k - 1.0) / k).sqrt();
    eprintln!("FENE scene: <Q^2> = {mean:.4} +- {se:.4} (exact 2)");
    assert!(se < 0.1, "{se}");
    assert!((mean - 2.0).abs() < 3.0 * se, "{mean} +- {se}");
}

/// A `rattle-stable` scene at temperature: a bonded trimer of
/// heavy spheres runs, the same seed gives the same bits, and a run resumed from its
/// checkpoint writes the bytes of one run (velocities and generator restored).
#[test]
fn rattle_stable_scene_at_temperature() {
    let scene_text = |duration: f64| {
        format!(
            "[fluid]\nviscosity = 0.05305164769729845\n[gravity]\nacceleration = [0.0, 0.0, 0.0]\n\
             [model]\nhydrodynamics = \"rpy\"\ninertia = true\noverlap = \"allow\"\n\
             [[particle]]\nposition = [0.0, 0.0, 0.0]\nradius = 1.0\ndensity = 0.238732414637843\n\
             [[particle]]\nposition = [3.0, 0.0, 0.0]\nradius = 1.0\ndensity = 0.238732414637843\n\
             [[particle]]\nposition = [3.0, 3.0, 0.0]\nradius = 1.0\ndensity = 0.238732414637843\n\
             [[bond]]\nbetween = [0, 1]\n[[bond]]\nbetween = [1, 2]\n\
             [integrator]\nmethod = \"rattle-stable\"\ndt = 0.01\nduration = {duration}\n\
             [output]\nevery = 10\n[brownian]\ntemperature = 1.0\nseed = 9\n"
        )
    };
    let s = Scene::parse(&scene_text(2.0), "trimer").unwrap();
    assert_eq!(s.brownian.map(|b| b.temperature), Some(1.0));
    let (a, b) = (last(&s), last(&s));
    assert_eq!(a, b);
    let cold = Scene::parse(
        &scene_text(2.0).replace("temperature = 1.0", "temperature = 0.0"),
        "cold",
    )
    .unwrap();
    assert_ne!(last(&cold), a, "the noise moves the beads");
    // Resume: 200 steps in one run, and 100 + 100 from the checkpoint.
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rattle-stable-restart");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (long, short) = (dir.join("long.toml"), dir.join("short.toml"));
    std::fs::write(&long, scene_text(2.0)).unwrap();
    std::fs::write(&short, scene_text(1.0)).unwrap();
    let (one, two) = run_and_resume(&dir, &long, &short, "0.5", "2");
    same_files(&one, &two, &["trajectory.xyz", "observables.csv"]);
}

/// Runs `long` in one go into `dir/one`, and `short` into `dir/two` with checkpoints
/// every `every`, then resumes `dir/two` until `until`; returns the two folders.
fn run_and_resume(
    dir: &std::path::Path,
    long: &std::path::Path,
    short: &std::path::Path,
    every: &str,
    until: &str,
) -> (std::path::PathBuf, std::path::PathBuf) {
    let (one, two) = (dir.join("one"), dir.join("two"));
    let (one_s, two_s) = (one.to_str().unwrap(), two.to_str().unwrap());
    ok(&["run", long.to_str().unwrap(), "--out", one_s]);
    let short = short.to_str().unwrap();
    ok(&["run", short, "--out", two_s, "--checkpoint-every", every]);
    ok(&["resume", two_s, "--until", until]);
    (one, two)
}

/// The files `names` are byte for byte the same in `a` and `b`.
fn same_files(a: &std::path::Path, b: &std::path::Path, names: &[&str]) {
    for f in names {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs after resume");
    }
}
