//! Sweeps: bad files refused at their line before anything runs; shards and processes
//! give byte-identical point folders; a killed shard rerun completes only what is
//! missing; the phase map as a sweep reproduces `phase`'s outcomes.

use crate::common::{BIN, cli, text};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use hydrorattle_host::scene::{Helix, Scene};
use hydrorattle_host::sweep::Sweep;

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/scenes")
}

fn sweeps() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/sweeps")
}

/// A sweep file in `dir` on the Figure 1 (a) scene with `body` after `[sweep]`.
fn sweep_file(dir: &Path, name: &str, body: &str) -> PathBuf {
    sweep_file_on(dir, name, "figure1a.toml", body)
}

/// A sweep file over the shipped scene `base`.
fn sweep_file_on(dir: &Path, name: &str, base: &str, body: &str) -> PathBuf {
    let path = dir.join(name);
    let base = scenes().join(base);
    let text = format!("[sweep]\nbase = {:?}\n{body}", base.display().to_string());
    std::fs::write(&path, text).unwrap();
    path
}

/// The error of a bad sweep file: at `name:line:`, and no folder written.
fn refused(dir: &Path, name: &str, body: &str, line: usize, says: &str) {
    let file = sweep_file(dir, name, body);
    let out = dir.join(format!("{name}.out"));
    let o = cli(&[
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let msg = text(&o);
    assert!(!o.status.success(), "{name} accepted: {msg}");
    let at = format!("{}:{line}:", file.display());
    assert!(msg.contains(&at), "{name}: expected {at} in {msg}");
    assert!(msg.contains(says), "{name}: expected {says:?} in {msg}");
    assert!(
        !out.exists(),
        "{name}: something was written before the check"
    );
}

#[test]
fn bad_sweep_files_are_refused_at_their_line_before_anything_runs() {
    let dir = empty_dir!("bad");
    // Line 1 is [sweep], line 2 the base.
    refused(
        &dir,
        "unknown.toml",
        "\"helix.dhat\" = [1.5]\n\"helix.colour\" = [1, 2]\n",
        4,
        "unknown field `colour`",
    );
    refused(&dir, "empty.toml", "\"helix.dhat\" = []\n", 3, "empty list");
    refused(
        &dir,
        "refused.toml",
        "\"integrator.dt\" = [0.1,\n  -0.05]\n",
        4,
        "dt must be > 0, not -0.05",
    );
    refused(
        &dir,
        "huge.toml",
        "\"helix.dhat\" = { linspace = [1.05, 2.0, 1000] }\n\"helix.head_ratio\" = { linspace = [1.0, 2.0, 1000] }\n\"integrator.dt\" = { linspace = [0.01, 0.1, 1000] }\n",
        4,
        "over the limit of 100000",
    );
    refused(
        &dir,
        "zip.toml",
        "[[sweep.zip]]\n\"helix.dhat\" = [1.05, 1.5]\n\"helix.head_ratio\" = [1.26]\n",
        5,
        "one length",
    );
    refused(
        &dir,
        "twice.toml",
        "\"helix.dhat\" = [1.5, 1.50]\n",
        3,
        "given twice",
    );
    refused(
        &dir,
        "replicas.toml",
        "\"helix.dhat\" = [1.5]\nreplicas = 3\n",
        4,
        "deterministic run",
    );
    refused(&dir, "index.toml", "\"particle.3.radius\" = [1.0]\n", 3, "");
    // A value the scene refuses only in combination: a head so small that the helix
    // generator refuses it, at the value's line.
    refused(
        &dir,
        "nested.toml",
        "\"helix.head_ratio\" = [1.26, 0.0]\n",
        3,
        "head_ratio must be > 0",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every file of every point folder under `a` and `b`, compared byte for byte except
/// `summary.json`, compared as JSON without its execution fields.
fn same_points(a: &Path, b: &Path) -> usize {
    let mut files = 0;
    let ids: Vec<_> = std::fs::read_dir(a.join("points"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    let ids_b = std::fs::read_dir(b.join("points")).unwrap().count();
    assert_eq!(ids.len(), ids_b, "point counts differ");
    for id in ids {
        let (pa, pb) = (a.join("points").join(&id), b.join("points").join(&id));
        let names: Vec<_> = std::fs::read_dir(&pa)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(
            names.len(),
            std::fs::read_dir(&pb).unwrap().count(),
            "{id:?}: files differ"
        );
        for name in names {
            let (x, y) = (
                std::fs::read(pa.join(&name)).unwrap(),
                std::fs::read(pb.join(&name)).unwrap(),
            );
            if name == "summary.json" {
                let strip = |bytes: &[u8]| {
                    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
                    for k in ["wall_time_s", "steps_per_second", "machine", "resumed_from"] {
                        v.as_object_mut().unwrap().remove(k);
                    }
                    v
                };
                assert_eq!(strip(&x), strip(&y), "{id:?}/summary.json");
            } else {
                assert!(x == y, "{id:?}/{name:?} differs");
            }
            files += 1;
        }
    }
    files
}

/// `collected.csv` without its last two columns (wall time, steps per second).
fn collected(dir: &Path) -> Vec<String> {
    let t = std::fs::read_to_string(dir.join("collected.csv")).unwrap();
    t.lines()
        .map(|l| l.rsplitn(3, ',').nth(2).unwrap().to_string())
        .collect()
}

#[test]
fn two_shards_in_parallel_give_what_one_process_gives() {
    let dir = empty_dir!("shards");
    let file = sweeps().join("small.toml");
    let file = file.to_str().unwrap();
    let (one, two) = (dir.join("one"), dir.join("two"));
    let o = cli(&["sweep", file, "--out", one.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let shard = |k: &str| {
        Command::new(BIN)
            .args([
                "sweep",
                file,
                "--out",
                two.to_str().unwrap(),
                "--shard",
                k,
                "--jobs",
                "1",
            ])
            .spawn()
            .unwrap()
    };
    let (mut a, mut b) = (shard("0/2"), shard("1/2"));
    assert!(a.wait().unwrap().success() && b.wait().unwrap().success());
    for d in [&one, &two] {
        let o = cli(&["collect", d.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
    }
    let files = same_points(&one, &two);
    assert_eq!(files, 8 * 7, "8 points of 7 files each");
    assert_eq!(collected(&one), collected(&two));
    assert_eq!(
        std::fs::read(one.join("sweep.json")).unwrap(),
        std::fs::read(two.join("sweep.json")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_killed_shard_rerun_completes_only_the_missing_points() {
    // Four points of 4000 steps, checkpoints every 20 time units (200 steps).
    killed_and_rerun(
        "kill",
        "figure1a.toml",
        "\"helix.dhat\" = [1.05, 1.2, 1.35, 1.5]\n",
        "20",
    );
}

/// Brownian points resume from their checkpoints too (the generator's state is in
/// them), to the bits of an uninterrupted run.
#[test]
fn a_killed_brownian_shard_resumes_to_the_same_bits() {
    // Four replicas of 4000 steps at kT = 0.5, checkpoints every 2 time units (400 steps).
    killed_and_rerun(
        "kill-brownian",
        "brownian_chain.toml",
        "replicas = 4\n\"integrator.duration\" = [20.0]\n\"output.every\" = [200]\n",
        "2",
    );
}

/// Runs the sweep `body` over `base` whole, and again killed (SIGKILL) once a point is
/// finished and another is midway, then rerun: only the missing points run, at least
/// one resumes from its checkpoint, and every file equals the whole run's.
fn killed_and_rerun(name: &str, base: &str, body: &str, every: &str) {
    let dir = empty_dir!(name);
    let file = sweep_file_on(&dir, "kill.toml", base, body);
    let file = file.to_str().unwrap();
    let (whole, killed) = (dir.join("whole"), dir.join("killed"));
    let args = |out: &Path| -> Vec<String> {
        [
            "sweep",
            file,
            "--out",
            out.to_str().unwrap(),
            "--jobs",
            "1",
            "--checkpoint-every",
            every,
        ]
        .map(String::from)
        .to_vec()
    };
    let o = Command::new(BIN).args(args(&whole)).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    // Kill it once a point is finished and another has a checkpoint but no summary.
    let mut child = Command::new(BIN)
        .args(args(&killed))
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let points = killed.join("points");
    let t0 = std::time::Instant::now();
    let caught = loop {
        let (mut done, mut midway) = (0, 0);
        for e in std::fs::read_dir(&points).into_iter().flatten().flatten() {
            let p = e.path();
            if p.join("summary.json").exists() {
                done += 1;
            } else if p.join("checkpoint.json").exists() {
                midway += 1;
            }
        }
        if done >= 1 && midway >= 1 {
            break true;
        }
        if child.try_wait().unwrap().is_some() || t0.elapsed().as_secs() > 120 {
            break false;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    assert!(caught, "the shard ended before it could be killed midway");
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let finished = std::fs::read_dir(&points)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().join("summary.json").exists())
        .count();
    assert!(finished < 4);
    let o = Command::new(BIN).args(args(&killed)).output().unwrap();
    let out = text(&o);
    assert!(o.status.success(), "{out}");
    let ran = 4 - finished;
    assert!(
        out.contains(&format!("ran {ran} of 4 points"))
            && out.contains(&format!("{finished} already finished")),
        "expected {ran} run and {finished} skipped: {out}"
    );
    assert!(
        out.contains("resumed from t = "),
        "no point was resumed: {out}"
    );
    same_points(&whole, &killed);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_phase_sweep_is_the_phase_grid() {
    let sweep = Sweep::from_path(&sweeps().join("phase.toml")).unwrap();
    let template = Scene::figure1().unwrap().remove(0).1;
    let base = template.helix.unwrap();
    let (ds, hs) = (
        hydrorattle_host::sweep::linspace(1.05, 2.0, 6),
        hydrorattle_host::sweep::linspace(1.0, 2.5, 6),
    );
    let cells: Vec<(f64, f64)> = hs
        .iter()
        .flat_map(|&h| ds.iter().map(move |&d| (d, h)))
        .collect();
    assert_eq!(sweep.points.len(), cells.len());
    for (p, &(d, h)) in sweep.points.iter().zip(&cells) {
        let helix = Helix {
            dhat: d,
            head_ratio: h,
            ..base
        };
        let cell = hydrorattle_study::phase::with_helix(&template, helix).unwrap();
        assert_eq!(
            p.scene, cell,
            "point {} is not the cell D = {d}, head = {h}",
            p.index
        );
    }
}

#[test]
fn sweep_and_collect_reproduce_the_phase_outcomes() {
    let dir = empty_dir!("phase");
    hydrorattle_study::phase::phase(&dir.join("phase"), 6, None).unwrap();
    let file = sweeps().join("phase.toml");
    let out = dir.join("sweep");
    let o = cli(&[
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = cli(&["collect", out.to_str().unwrap()]);
    let phase = std::fs::read_to_string(dir.join("phase/phase.csv")).unwrap();
    let want: BTreeMap<(String, String), String> = phase
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            ((f[0].to_string(), f[1].to_string()), f[2].to_string())
        })
        .collect();
    let table = std::fs::read_to_string(out.join("collected.csv")).unwrap();
    let header: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (d, h, outcome) = (col("helix.dhat"), col("helix.head_ratio"), col("outcome"));
    let got: BTreeMap<(String, String), String> = table
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            ((f[d].to_string(), f[h].to_string()), f[outcome].to_string())
        })
        .collect();
    assert_eq!(got.len(), 36);
    assert_eq!(got, want);
    // collect fails exactly when some cell failed.
    assert_eq!(
        o.status.success(),
        !want.values().any(|v| v == "failed"),
        "{}",
        text(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_point_with_level_auto_is_finished_once_run() {
    // Its scene.toml is written with the auto choice applied, as the run records it, so
    // the second invocation finds it finished.
    let dir = empty_dir!("auto");
    let path = dir.join("auto.toml");
    let base = scenes().join("dimer.toml");
    let file = format!(
        "[sweep]\nbase = {:?}\n\"model.level\" = [\"auto\"]\n\"integrator.dt\" = [0.01, 0.02]\n",
        base.display().to_string()
    );
    std::fs::write(&path, file).unwrap();
    let out = dir.join("out");
    let run = || {
        cli(&[
            "sweep",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let first = text(&run());
    assert!(first.contains("ran 2 of 2 points"), "{first}");
    let second = text(&run());
    assert!(
        second.contains("ran 0 of 2 points") && second.contains("2 already finished"),
        "{second}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
