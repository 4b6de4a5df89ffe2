//! End-to-end runs: every shipped scene runs, the files of a run are whole and
//! consistent, and a bad scene stops the CLI with file and line before any output.

use crate::common::{cli, manifest};
use std::path::{Path, PathBuf};

use hydrorattle_host::output::read_xyz_file;
use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::{COLUMNS, RunOptions, run};

#[test]
fn every_shipped_scene_runs_and_writes_whole_files() {
    for entry in std::fs::read_dir(manifest().join("../host/scenes")).unwrap() {
        let path = entry.unwrap().path();
        let scene = Scene::from_path(&path).unwrap();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let out = scratch!(&name);
        let opts = RunOptions {
            progress: false,
            max_steps: Some(300),
            ..Default::default()
        };
        let r = run(&scene, &name, Some(&out), opts).unwrap();
        assert_eq!(r.summary.failure, None, "{name}");
        assert_eq!(
            r.summary.steps_done,
            300.min(scene.integrator.steps()),
            "{name}"
        );
        let frames = read_xyz_file(&out.join("trajectory.xyz")).unwrap();
        assert_eq!(
            frames.len(),
            r.series.len(),
            "{name}: one frame per observables row"
        );
        assert_eq!(frames[0].positions.len(), scene.particles.len());
        // The last frame is the final state, bit for bit.
        assert_eq!(frames.last().unwrap().positions, r.last.positions, "{name}");
        let csv = std::fs::read_to_string(out.join("observables.csv")).unwrap();
        assert_eq!(csv.lines().next().unwrap(), COLUMNS.join(","));
        assert_eq!(csv.lines().count(), r.series.len() + 1);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["steps_done"], r.summary.steps_done);
        // No temporary file is left behind.
        for f in std::fs::read_dir(&out).unwrap() {
            assert!(!f.unwrap().path().to_string_lossy().ends_with(".tmp"));
        }
        // Bonds held to the tolerance the run used.
        let worst = r.series.iter().map(|o| o.bond_residual).fold(0.0, f64::max);
        if scene.integrator.method != hydrorattle_host::scene::Method::Springs {
            assert!(
                worst <= 10.0 * r.summary.tolerance_used,
                "{name}: {worst:e}"
            );
        }
        std::fs::remove_dir_all(&out).unwrap();
    }
}

#[test]
fn a_bad_scene_stops_the_cli_with_file_and_line_before_any_output() {
    let bad = manifest().join("tests/data/bad");
    let mut checked = 0;
    for entry in std::fs::read_dir(&bad).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let out = scratch!(&format!("bad-{checked}"));
        let o = cli(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success(), "{}", path.display());
        let err = String::from_utf8_lossy(&o.stderr);
        let shown = format!("{}:", path.display());
        assert!(err.contains(&shown), "{err}");
        assert!(
            !Path::new(&out).exists(),
            "{}: output written for a bad scene",
            path.display()
        );
        checked += 1;
    }
    assert!(checked >= 10);
}

#[test]
fn figure1_quick_writes_its_picture_and_table() {
    let out = scratch!("figure1");
    let o = cli(&["figure1", "--quick", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("figure1.png").metadata().unwrap().len() > 10_000);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("figure1.json")).unwrap()).unwrap();
    let cases = j["cases"].as_array().unwrap();
    let names: Vec<&str> = cases.iter().map(|c| c["case"].as_str().unwrap()).collect();
    assert_eq!(names, ["a", "b", "c"]);
    for c in cases {
        for key in [
            "dhat",
            "head_ratio",
            "extension",
            "verticality",
            "twist_rate",
            "head_speed",
        ] {
            assert!(c[key].is_number(), "{key}");
        }
        assert!(c["outcome"].is_string());
        assert!(
            out.join(c["case"].as_str().unwrap())
                .join("summary.json")
                .exists()
        );
    }
    std::fs::remove_dir_all(&out).unwrap();
}

/// Writes `text` as `name.toml` in a fresh scratch folder and runs it: the output, the
/// output folder.
fn run_text(name: &str, text: &str) -> (std::process::Output, PathBuf) {
    let dir = scratch!(name);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let o = cli(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    (o, out)
}

/// A sphere touching a wall far from the origin (`z = h + r` rounds) and an f32 sphere
/// just above the wall that rounds below it both run: touching is to the rounding of
/// the coordinates, in the scene and in the kernel. The f32 sphere is pulled along the
/// wall with steps long enough to move it by its coordinates' spacing (shorter ones
/// are refused: its position would not change).
#[test]
fn spheres_touching_a_wall_to_the_rounding_run() {
    let scenes = [
        (
            "far-wall",
            "-1e6",
            "-999999.9",
            "0.1",
            "f64",
            "",
            ("0.01", "0.1"),
        ),
        (
            "f32-wall",
            "1000.0",
            "1000.0010001",
            "0.001",
            "f32",
            "[gravity]\nacceleration = [1.0, 0.0, 0.0]\n\n",
            ("1000.0", "10000.0"),
        ),
    ];
    for (name, h, z, r, precision, g, (dt, duration)) in scenes {
        let text = format!(
            "{g}[wall]\nheight = {h}\n\n\
             [[particle]]\nposition = [0.0, 0.0, {z}]\nradius = {r}\n\n\
             [integrator]\nmethod = \"overdamped\"\ndt = {dt}\nduration = {duration}\nprecision = \"{precision}\"\n"
        );
        let (o, out) = run_text(name, &text);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(out.join("summary.json").exists());
    }
}

/// Two spheres under vorticity 100 at dt 0.1 turn 10 rad a step: the
/// explicit flow term grows their radius tenfold a step until f32's squares overflow
/// (NaN observables). A rotation no step follows is refused at its line, in either
/// precision, before any folder exists; at dt 0.01 (1 rad a step) it runs.
#[test]
fn a_rotation_faster_than_the_step_is_refused_at_its_line() {
    for precision in ["f32", "f64"] {
        let scene = |dt: f64| {
            format!(
                "[flow]\nvorticity = [0.0, 0.0, 100.0]\n\n[[particle]]\nposition = [0.0, 0.0, 0.0]\nradius = 1.0\n\n\
                 [[particle]]\nposition = [3.0, 0.0, 0.0]\nradius = 1.0\n\n\
                 [integrator]\nmethod = \"overdamped\"\ndt = {dt}\nduration = 1.0\nprecision = \"{precision}\"\n"
            )
        };
        let (o, out) = run_text(&format!("vortex-{precision}"), &scene(0.1));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(".toml:2:") && err.contains("rad per step"),
            "{err}"
        );
        assert!(!out.exists(), "a refused scene leaves no folder");
        let (o, out) = run_text(&format!("vortex-slow-{precision}"), &scene(0.01));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        let rows = std::fs::read_to_string(out.join("observables.csv")).unwrap();
        assert!(!rows.contains("NaN") && !rows.contains("inf"), "{rows}");
    }
}
