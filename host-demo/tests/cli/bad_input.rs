//! Every bad input is refused cleanly by the real `host-demo run`: the file and the
//! line in the message, exit status 1, no panic, no output folder, an answer within a
//! second (limits are checked before any work). Faults while writing (a full disk, a
//! read-only folder) name the file and leave no `*.tmp` behind.

use crate::common::{BIN, manifest};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// Runs `host-demo run SCENE --out OUT`; the output and the wall time.
fn run(scene: &Path, out: &Path, extra: &[&str]) -> (Output, Duration) {
    let t = Instant::now();
    let o = Command::new(BIN)
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    (o, t.elapsed())
}

fn expect_line(path: &Path) -> usize {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .find_map(|l| l.strip_prefix("# expect-line:"))
        .unwrap_or_else(|| panic!("{} has no expect-line", path.display()))
        .trim()
        .parse()
        .unwrap()
}

/// A refusal as the issue asks for it: exit 1, one `error: FILE:LINE:` line, no panic.
fn assert_refused(o: &Output, file: &Path, line: Option<usize>) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{}: {err}", file.display());
    assert!(!err.contains("panicked"), "{err}");
    let prefix = match line {
        Some(l) => format!("error: {}:{l}:", file.display()),
        None => format!("error: {}", file.display()),
    };
    assert!(err.starts_with(&prefix), "want {prefix:?}, got {err}");
    err
}

/// A write fault: exit 1, no panic, the message names the file `name` in `out`.
fn assert_names_file(o: &Output, out: &Path, name: &str) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let file = out.join(name).display().to_string();
    assert!(err.contains(&file), "the message names the file: {err}");
    err
}

fn tmp_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|d| {
            d.map(|e| e.unwrap().path())
                .filter(|p| p.to_string_lossy().ends_with(".tmp"))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn every_bad_scene_is_refused_at_its_line_within_a_second_and_writes_nothing() {
    let dir = manifest().join("tests/data/bad");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 40, "{} bad scenes", files.len());
    for (k, path) in files.iter().enumerate() {
        let out = scratch!(&format!("scene-{k}"));
        let (o, took) = run(path, &out, &[]);
        assert_refused(&o, path, Some(expect_line(path)));
        assert!(
            took < Duration::from_secs(1),
            "{}: {took:?}",
            path.display()
        );
        assert!(!out.exists(), "{}: output folder left", path.display());
    }
}

#[test]
fn invalid_utf8_is_refused_at_its_line() {
    let dir = scratch!("utf8");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("latin1.toml");
    let text = b"[helix]\ntails = 3\n\n# caf\xe9 au lait\n[integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 1.0\n";
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let (o, _) = run(&scene, &out, &[]);
    let err = assert_refused(&o, &scene, Some(4));
    assert!(err.contains("UTF-8"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_full_disk_names_the_file_and_leaves_no_tmp_and_no_folder_of_its_own() {
    if !Path::new("/dev/full").exists() {
        eprintln!("no /dev/full here: skipped");
        return;
    }
    // The trajectory's temporary name points at /dev/full: every write fails with
    // "no space left on device", as on a full disk.
    let out = scratch!("full");
    std::fs::create_dir_all(&out).unwrap();
    std::os::unix::fs::symlink("/dev/full", out.join("trajectory.xyz.tmp")).unwrap();
    let scene = manifest().join("../host/scenes/dimer.toml");
    let (o, _) = run(&scene, &out, &[]);
    let err = assert_names_file(&o, &out, "trajectory.xyz");
    assert!(err.to_lowercase().contains("space"), "{err}");
    assert_eq!(tmp_files(&out), Vec::<PathBuf>::new());
    assert!(!out.join("summary.json").exists());
}

#[test]
fn a_read_only_folder_names_the_file_and_leaves_nothing() {
    let out = scratch!("read-only");
    std::fs::create_dir_all(&out).unwrap();
    let lock = |on: bool| {
        // chmod stops a normal user; root needs the immutable flag as well.
        let (mode, flag) = if on { ("555", "+i") } else { ("755", "-i") };
        let chmod = || Command::new("chmod").arg(mode).arg(&out).output();
        let chattr = || Command::new("chattr").arg(flag).arg(&out).output();
        if on {
            let _ = (chmod(), chattr());
        } else {
            let _ = (chattr(), chmod());
        }
    };
    lock(true);
    if std::fs::write(out.join("probe"), b"").is_ok() {
        lock(false);
        eprintln!("cannot make a read-only folder here: skipped");
        return;
    }
    let scene = manifest().join("../host/scenes/dimer.toml");
    let (o, took) = run(&scene, &out, &[]);
    lock(false);
    // The resolved scene is the first file a run writes (so that a killed run resumes).
    assert_names_file(&o, &out, "scene.toml");
    assert!(took < Duration::from_secs(1));
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0);
}

#[test]
fn an_output_path_that_is_a_file_is_refused_by_name() {
    let dir = scratch!("file-out");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("not-a-folder");
    std::fs::write(&out, b"x").unwrap();
    let (o, _) = run(&manifest().join("../host/scenes/dimer.toml"), &out, &[]);
    let err = assert_refused(&o, &out, None);
    assert!(!err.contains("panicked"));
    assert_eq!(std::fs::read(&out).unwrap(), b"x");
}
