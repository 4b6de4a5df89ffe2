//! The record of a run: `summary.json` holds what is needed to rerun it, `scene.toml`
//! re-runs to the same bytes, `observables.csv` ends where the summary ends, and a run
//! to `T` resumed to `2 T` writes the same bytes as one run to `2 T`.

use crate::common::{BIN, manifest, ok};
use std::path::Path;
use std::process::Command;

fn run(scene: &Path, out: &Path, extra: &[&str]) {
    let mut args = vec![
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    ok(&args);
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn bytes(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{}: {e}", dir.join(name).display()))
}

const TRAJECTORY_FILES: [&str; 3] = ["trajectory.xyz", "trajectory.gsd", "observables.csv"];

#[test]
fn the_summary_records_what_a_rerun_needs() {
    let scene = manifest().join("../host/scenes/dimer.toml");
    let out = scratch!("summary");
    run(&scene, &out, &[]);
    let s = json(&out.join("summary.json"));
    for key in [
        "fluid",
        "gravity",
        "flow",
        "precision",
        "machine",
        "resolved_scene",
    ] {
        assert!(!s[key].is_null(), "summary.json lacks {key}");
    }
    assert_eq!(s["scene_path"], scene.display().to_string());
    let version = s["code_version"].as_str().unwrap();
    assert!(version.starts_with(env!("CARGO_PKG_VERSION")), "{version}");
    // The commit's name has a fixed length, whatever the repository's object count.
    let inner = version.split(['(', ')']).nth(1).unwrap_or_default();
    if inner != "no git" {
        let hash = inner
            .trim_end_matches("-dirty")
            .rsplit(['-', 'g'])
            .next()
            .unwrap();
        assert_eq!(hash.len(), 12, "{version}");
        assert!(hash.chars().all(|c| c.is_ascii_hexdigit()), "{version}");
    }
    assert!(s["machine"]["cpus"].as_u64().unwrap() >= 1);
    assert_eq!(s["resolved_scene"]["model"]["level"], "manual");
    assert_eq!(
        s["resolved_scene"]["output"]["every"],
        s["integrator"]["duration"].as_f64().unwrap()
            / s["integrator"]["dt"].as_f64().unwrap()
            / 200.0
    );
}

#[test]
fn the_last_row_of_the_observables_is_the_summary_s_final_observables() {
    // A step count that is not a multiple of `every`: the last frame is off schedule.
    let dir = scratch!("last-row");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("odd.toml");
    let text = std::fs::read_to_string(manifest().join("../host/scenes/dimer.toml")).unwrap();
    assert!(text.contains("every = 10"));
    let text = text.replace("every = 10", "every = 7");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    run(&scene, &out, &[]);
    let s = json(&out.join("summary.json"));
    let csv = String::from_utf8(bytes(&out, "observables.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let last: Vec<&str> = csv.lines().last().unwrap().split(',').collect();
    let f = &s["final_observables"];
    assert_eq!(header.len(), last.len());
    for (name, value) in header.iter().zip(&last) {
        let want = match *name {
            "com_x" => &f["com"][0],
            "com_y" => &f["com"][1],
            "com_z" => &f["com"][2],
            n => &f[n],
        };
        if *name == "state" {
            assert_eq!(want.as_str().unwrap(), *value, "{name}");
        } else if value.is_empty() {
            // The wall's columns without a wall: absent from the summary too.
            assert!(want.is_null(), "{name}: empty cell, summary {want}");
        } else {
            let value: f64 = value.parse().unwrap();
            assert_eq!(want.as_f64().unwrap(), value, "{name}");
        }
    }
    assert!(
        f["iterations"].as_u64().unwrap() > 0,
        "the last step's iterations"
    );
}

#[test]
fn the_resolved_scene_reruns_to_the_same_bytes() {
    for (name, scene) in [
        ("helix", "../host/scenes/figure1c.toml"),
        ("explicit", "../host/scenes/tree.toml"),
    ] {
        let first = scratch!(&format!("first-{name}"));
        run(&manifest().join(scene), &first, &[]);
        let again = scratch!(&format!("again-{name}"));
        run(&first.join("scene.toml"), &again, &[]);
        for f in TRAJECTORY_FILES.iter().chain(&["scene.toml"]) {
            assert!(bytes(&first, f) == bytes(&again, f), "{name}: {f} differs");
        }
    }
}

#[test]
fn a_run_resumed_from_its_checkpoint_writes_the_same_bytes_as_one_run() {
    // An inertial scene with initial velocities, ending off the frame schedule at T.
    let dir = scratch!("restart");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("spin.toml");
    std::fs::write(
        &scene,
        "[[particle]]\nposition = [0, 0, 0]\nradius = 1.5\nvelocity = [0.3, 0, 0]\n\n\
         [[particle]]\nposition = [3, 0, 1]\nradius = 1\nvelocity = [0, 0.2, -0.1]\nspecies = \"small\"\n\n\
         [[particle]]\nposition = [6, 0, 2]\nradius = 1\n\n\
         [[bond]]\nbetween = [0, 1]\n\n[[bond]]\nbetween = [1, 2]\n\n\
         [integrator]\nmethod = \"rattle-stable\"\ndt = 0.01\nduration = 4.0\n\n\
         [output]\nevery = 7\n",
    )
    .unwrap();
    let one = dir.join("one");
    let mut long = std::fs::read_to_string(&scene).unwrap();
    long = long.replace("duration = 4.0", "duration = 8.0");
    let long_scene = dir.join("long.toml");
    std::fs::write(&long_scene, long).unwrap();
    run(&long_scene, &one, &[]);

    let two = dir.join("two");
    run(&scene, &two, &["--checkpoint-every", "4"]);
    let c = json(&two.join("checkpoint.json"));
    assert_eq!(c["step"], 400);
    ok(&["resume", two.to_str().unwrap(), "--until", "8"]);
    for f in TRAJECTORY_FILES {
        assert!(bytes(&one, f) == bytes(&two, f), "{f} differs after resume");
    }
    let (s1, s2) = (
        json(&one.join("summary.json")),
        json(&two.join("summary.json")),
    );
    assert!((s2["resumed_from"].as_f64().unwrap() - 4.0).abs() < 1e-9);
    for key in [
        "final_observables",
        "twist_rate",
        "steps_done",
        "mean_iterations",
    ] {
        assert_eq!(s1[key], s2[key], "{key}");
    }
}

/// The files of the finished run in `dir` as a run killed after its checkpoint leaves
/// them: under their temporary names, with what it wrote past the checkpoint.
fn as_if_killed(dir: &Path) {
    for f in TRAJECTORY_FILES {
        let mut partial = bytes(dir, f);
        partial.extend_from_slice(b"frames written after the checkpoint, then killed");
        std::fs::write(dir.join(format!("{f}.tmp")), partial).unwrap();
        std::fs::remove_file(dir.join(f)).unwrap();
    }
}

#[test]
fn a_killed_run_resumes_from_the_files_it_left() {
    // A killed run leaves its files under their temporary names, with frames past the
    // checkpoint: resume cuts them back and continues, to the bytes of one run.
    let dir = scratch!("killed");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(manifest().join("../host/scenes/ring.toml")).unwrap();
    let scene = |name: &str, duration: &str| {
        let path = dir.join(name);
        // A fixed `every`: the default depends on the duration.
        let t = text.replace("duration = 20.0", &format!("duration = {duration}"))
            + "\n[output]\nevery = 3\n";
        std::fs::write(&path, t).unwrap();
        path
    };
    let one = dir.join("one");
    run(&scene("long.toml", "4.0"), &one, &[]);
    let killed = dir.join("killed");
    run(
        &scene("short.toml", "2.0"),
        &killed,
        &["--checkpoint-every", "2"],
    );
    as_if_killed(&killed);
    ok(&["resume", killed.to_str().unwrap(), "--until", "4"]);
    for f in TRAJECTORY_FILES {
        assert!(bytes(&one, f) == bytes(&killed, f), "{f} differs");
        assert!(!killed.join(format!("{f}.tmp")).exists());
    }
}

#[test]
fn a_run_killed_after_a_checkpoint_on_its_last_step_resumes_to_one_run() {
    // A dimer of 95 steps, a frame every 10, a checkpoint every 19: the last checkpoint
    // is on the last step, which is no frame step, so the run's closing row comes after
    // it. Killed there (files under their temporary names, no summary), the run is
    // finished by `resume --until` its own end, with the closing row of the
    // uninterrupted run (that step's iterations and tension, not zeros), and goes on
    // from there as one longer run.
    let dir = scratch!("last-step");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(manifest().join("../host/scenes/dimer.toml")).unwrap();
    let scene = |name: &str, duration: &str| {
        let path = dir.join(name);
        std::fs::write(
            &path,
            text.replace("duration = 20.0", &format!("duration = {duration}")),
        )
        .unwrap();
        path
    };
    let (one, longer) = (dir.join("one"), dir.join("longer"));
    run(&scene("one.toml", "0.95"), &one, &[]);
    run(&scene("longer.toml", "1.33"), &longer, &[]);
    let killed = dir.join("killed");
    run(
        &scene("killed.toml", "0.95"),
        &killed,
        &["--checkpoint-every", "0.19"],
    );
    assert_eq!(json(&killed.join("checkpoint.json"))["step"], 95);
    std::fs::remove_file(killed.join("summary.json")).unwrap();
    as_if_killed(&killed);
    ok(&["resume", killed.to_str().unwrap(), "--until", "0.95"]);
    let rows = String::from_utf8(bytes(&killed, "observables.csv")).unwrap();
    let last: Vec<&str> = rows.lines().last().unwrap().split(',').collect();
    assert!(
        last[10] != "0",
        "the closing row records its step's solve: {last:?}"
    );
    for (done, until) in [(&one, "0.95"), (&longer, "1.33")] {
        if until != "0.95" {
            ok(&["resume", killed.to_str().unwrap(), "--until", until]);
        }
        for f in TRAJECTORY_FILES {
            assert!(
                bytes(done, f) == bytes(&killed, f),
                "{f} differs at {until}"
            );
        }
        let (s1, s2) = (
            json(&done.join("summary.json")),
            json(&killed.join("summary.json")),
        );
        for key in [
            "final_observables",
            "twist_rate",
            "steps_done",
            "mean_iterations",
        ] {
            assert_eq!(s1[key], s2[key], "{key} at {until}");
        }
    }
}

/// A run written before `observables.csv` gained the wall's three columns is refused
/// by `resume` with an error that names the file and the columns it lacks, before any
/// file is touched (no migration).
#[test]
fn a_run_of_an_older_version_is_refused_with_the_columns_named() {
    let old = scratch!("older");
    run(
        &manifest().join("../host/scenes/dimer.toml"),
        &old,
        &["--checkpoint-every", "10"],
    );
    // The file as the older version wrote it: without the wall's columns.
    let csv = old.join("observables.csv");
    let text = String::from_utf8(bytes(&old, "observables.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let keep: Vec<bool> = header.iter().map(|c| !c.starts_with("wall_")).collect();
    assert_eq!(keep.iter().filter(|k| !**k).count(), 3);
    let older: String = text
        .lines()
        .map(|l| {
            let cells = l.split(',').zip(&keep).filter(|(_, k)| **k);
            cells.map(|(c, _)| c).collect::<Vec<_>>().join(",") + "\n"
        })
        .collect();
    std::fs::write(&csv, &older).unwrap();
    let listing = |d: &Path| {
        let mut names: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        names
    };
    let before = listing(&old);

    let opts = hydrorattle_host::sim::RunOptions::default();
    let limits = hydrorattle_host::sizing::Limits::default();
    let e = hydrorattle_host::sim::resume(&old, 40.0, limits, opts).unwrap_err();
    let m = e
        .downcast_ref::<hydrorattle_host::sim::ColumnsMismatch>()
        .unwrap_or_else(|| panic!("not a ColumnsMismatch: {e:#}"));
    assert_eq!(m.path, csv);
    assert_eq!(m.missing, ["wall_height", "wall_gap", "wall_contacts"]);
    assert!(m.unknown.is_empty());
    assert_eq!(m.found.len(), 21);
    // The command line says the same, and nothing changed.
    let o = Command::new(BIN)
        .args(["resume", old.to_str().unwrap(), "--until", "40"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    let said = format!(
        "{}: 21 columns where this program writes 24; it lacks wall_height, wall_gap, \
         wall_contacts",
        csv.display()
    );
    assert!(stderr.contains(&said), "{stderr}");
    assert_eq!(bytes(&old, "observables.csv"), older.as_bytes());
    assert_eq!(listing(&old), before);
}
