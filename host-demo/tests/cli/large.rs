//! Thousands of beads through the real `host-demo run`: a 4096-bead helix steps with
//! its bonds held, and a scene too large for the storage limit is refused at once, at
//! its line, before anything is written.

use crate::common::{BIN, manifest};
use std::process::Command;
use std::time::{Duration, Instant};

use hydrorattle_host::output::read_xyz_file;
use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::{BuildError, RunOptions, run};

fn cli_run(args: &[&str]) -> std::process::Output {
    Command::new(BIN).arg("run").args(args).output().unwrap()
}

#[test]
fn a_4096_bead_helix_steps_with_its_bonds_held() {
    let scene = manifest().join("tests/data/helix4096.toml");
    let out = scratch!("helix4096");
    let o = cli_run(&[scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["particles"], 4096);
    assert_eq!(summary["bonds"], 4095);
    assert_eq!(summary["steps"], 3);
    assert_eq!(summary["steps_done"], 3);
    assert!(summary["failure"].is_null(), "{}", summary["failure"]);
    // Every recorded frame holds every bond to the tolerance (f64, 1e-10).
    let tolerance = summary["tolerance_used"].as_f64().unwrap();
    let csv = std::fs::read_to_string(out.join("observables.csv")).unwrap();
    let residuals: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(9).unwrap().parse().unwrap())
        .collect();
    assert_eq!(residuals.len(), 4, "the initial frame and one per step");
    for r in &residuals {
        assert!(*r <= 10.0 * tolerance, "bond residual {r:e}");
    }
    // The whole chain is in the trajectory, and it moved: it settles along gravity.
    let frames = read_xyz_file(&out.join("trajectory.xyz")).unwrap();
    let (first, last) = (&frames[0], frames.last().unwrap());
    assert_eq!(last.positions.len(), 4096);
    let drop = first.positions[0][2] - last.positions[0][2];
    assert!(drop > 0.0, "the head moved down by {drop}");
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn ten_million_tails_are_refused_at_once_at_their_line() {
    let scene = manifest().join("tests/data/bad/helix_too_large.toml");
    let out = scratch!("too-large");
    let start = Instant::now();
    let o = cli_run(&[scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let took = start.elapsed();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("{}:7:", scene.display())), "{err}");
    assert!(err.contains("over the limit of 8.0 GiB"), "{err}");
    assert!(!out.exists(), "nothing may be written");
    assert!(took < Duration::from_secs(1), "refused after {took:?}");
}

#[test]
fn the_limit_can_be_raised_or_lowered() {
    let scene = manifest().join("../host/scenes/figure1a.toml");
    let out = scratch!("limit");
    // The 25-bead chain needs tens of kB: 1 kB is too little.
    let o = cli_run(&[
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--max-storage",
        "0.000001",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("scenes/figure1a.toml:"), "{err}");
    assert!(err.contains("step storage"), "{err}");
    assert!(!out.exists());
    let o = cli_run(&[scene.to_str().unwrap(), "--out", "x", "--max-storage", "0"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("positive number of GiB"));
}

#[test]
fn the_library_refuses_an_oversized_run_with_a_typed_error() {
    let scene = Scene::figure1().unwrap().remove(0).1;
    let opts = RunOptions {
        max_storage: 1024,
        ..Default::default()
    };
    let e = run(&scene, "a", None, opts).unwrap_err();
    let Some(BuildError::TooLarge(t)) = e.downcast_ref::<BuildError>() else {
        panic!("{e:#}");
    };
    assert_eq!((t.particles, t.bonds, t.limit), (25, 24, 1024));
}

/// The 4096-bead Brownian chain (`tests/data/brownian_chain4096.toml`, matrix-free, kT
/// = 0.5) cut to 256 beads so it runs in a moment: it runs through `host-demo run`,
/// keeps its bonds, stores no mobility, and gives the same bits on one thread and on
/// two, and again with the same seed. The whole file: `host-demo run
/// host-demo/tests/data/brownian_chain4096.toml --out DIR` (about 5 s a step on one
/// core, 7.6 MiB of step storage).
#[test]
fn a_matrix_free_brownian_chain_runs_with_the_same_bits_on_any_threads() {
    let text = std::fs::read_to_string(manifest().join("tests/data/brownian_chain4096.toml"))
        .unwrap()
        .replace("tails = 4095", "tails = 255");
    let dir = scratch!("bd256");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("bd256.toml");
    std::fs::write(&scene, text).unwrap();
    let go = |name: &str, threads: &str| {
        let out = dir.join(name);
        let o = cli_run(&[
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--threads",
            threads,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["particles"], 256);
        assert_eq!(summary["steps_done"], 2);
        assert!(summary["failure"].is_null(), "{}", summary["failure"]);
        read_xyz_file(&out.join("trajectory.xyz"))
            .unwrap()
            .last()
            .unwrap()
            .positions
            .clone()
    };
    let one = go("one", "1");
    assert_eq!(one, go("two", "2"), "threads changed the bits");
    assert_eq!(one, go("again", "1"), "same seed, different bits");
    // Bonds held; the noise moved the chain.
    let start = read_xyz_file(&dir.join("one/trajectory.xyz")).unwrap()[0]
        .positions
        .clone();
    assert_ne!(start, one);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("one/summary.json")).unwrap())
            .unwrap();
    let tolerance = summary["tolerance_used"].as_f64().unwrap();
    let csv = std::fs::read_to_string(dir.join("one/observables.csv")).unwrap();
    for l in csv.lines().skip(1) {
        let r: f64 = l.split(',').nth(9).unwrap().parse().unwrap();
        assert!(r <= 10.0 * tolerance, "bond residual {r:e}");
    }
    // No stored mobility: the plan's storage is O(N) (the 256-bead stored thermal
    // layout would hold two packed mobilities, 2 x 2.4 MB).
    let s = Scene::from_path(&scene).unwrap();
    let bytes = hydrorattle_host::sizing::Plan::of(&s)
        .bytes(256, 255)
        .unwrap();
    assert!(bytes < 1_000_000, "{bytes} bytes of step storage");
    std::fs::remove_dir_all(&dir).unwrap();
}
