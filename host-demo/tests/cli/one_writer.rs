//! One writer per output folder: two processes on one sweep point, 20 times over, end
//! as one clean run (the second skips the locked point, or finds it finished), and
//! `collect` reports a point done only when its files are those its summary records.
//! A point held by another process is skipped and said, or waited for with `--wait`;
//! a plain `run` into a folder another process writes is refused before it writes.

use crate::common::{BIN, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use hydrorattle_host::output::FolderLock;

const DATA: [&str; 5] = [
    "observables.csv",
    "trajectory.xyz",
    "trajectory.gsd",
    "scene.toml",
    "signac_statepoint.json",
];

fn small() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/sweeps/small.toml")
}

fn sweep(out: &Path, id: &str) -> Command {
    let mut c = Command::new(BIN);
    c.arg("sweep")
        .arg(small())
        .arg("--out")
        .arg(out)
        .args(["--point", id, "--jobs", "1"]);
    c
}

/// The first point's id.
fn first_point() -> String {
    let o = Command::new(BIN)
        .arg("sweep")
        .arg(small())
        .args(["--out", "unused", "--dry-run"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    out.split_whitespace().next().unwrap().to_string()
}

/// `summary.json` without the fields of the execution (machine, times).
fn summary(dir: &Path) -> serde_json::Value {
    let bytes = std::fs::read(dir.join("summary.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    for k in ["wall_time_s", "steps_per_second", "machine"] {
        v.as_object_mut().unwrap().remove(k);
    }
    v
}

/// `host-demo collect DIR`: its output and success.
fn collect(dir: &Path) -> (bool, String) {
    let o = Command::new(BIN).arg("collect").arg(dir).output().unwrap();
    (o.status.success(), text(&o))
}

#[test]
fn two_processes_on_one_point_end_as_one_clean_run_twenty_times_over() {
    let root = empty_dir!("twice");
    let id = first_point();
    let clean = root.join("clean");
    let o = sweep(&clean, &id).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let clean_point = clean.join("points").join(&id);
    let (mut equal, mut locked) = (0, 0);
    for k in 0..20 {
        let out = root.join(format!("run-{k}"));
        let spawn = || {
            sweep(&out, &id)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (spawn(), spawn());
        let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
        let said = format!("{}\n{}", text(&a), text(&b));
        assert!(a.status.success() && b.status.success(), "try {k}: {said}");
        // One ran it; the other skipped it, locked or already finished.
        assert_eq!(said.matches(": ran, ").count(), 1, "try {k}: {said}");
        locked += said.matches("skipped: locked by another process").count() / 2;
        let point = out.join("points").join(&id);
        for name in DATA {
            let (x, y) = (
                std::fs::read(clean_point.join(name)).unwrap(),
                std::fs::read(point.join(name)).unwrap(),
            );
            assert!(x == y, "try {k}: {name} differs from a clean run's");
        }
        assert_eq!(summary(&clean_point), summary(&point), "try {k}");
        let (ok, said) = collect(&out);
        // The other points were never run: the one run is done.
        assert!(!ok, "try {k}: {said}");
        assert!(!said.contains(&id), "try {k}: {id} not done: {said}");
        let table = std::fs::read_to_string(out.join("collected.csv")).unwrap();
        let row = table.lines().find(|l| l.starts_with(&id)).unwrap();
        assert!(row.contains(",done,"), "try {k}: {row}");
        equal += 1;
    }
    eprintln!(
        "{equal} of 20 equal to a clean run; the second found the point locked {locked} times"
    );
    assert_eq!(equal, 20);
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn collect_reports_a_cut_trajectory_corrupt_not_done() {
    let root = empty_dir!("cut");
    let id = first_point();
    let o = sweep(&root, &id).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let gsd = root.join("points").join(&id).join("trajectory.gsd");
    let len = std::fs::metadata(&gsd).unwrap().len();
    let file = std::fs::OpenOptions::new().write(true).open(&gsd).unwrap();
    file.set_len(len / 2).unwrap();
    let (ok, said) = collect(&root);
    assert!(!ok);
    let line = said.lines().find(|l| l.starts_with(&id)).unwrap();
    assert!(line.contains(" corrupt "), "{line}");
    assert!(line.contains(&gsd.display().to_string()), "{line}");
    let table = std::fs::read_to_string(root.join("collected.csv")).unwrap();
    let row = table.lines().find(|l| l.starts_with(&id)).unwrap();
    assert!(row.contains(",corrupt,"), "{row}");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_run_into_a_folder_another_process_writes_is_refused_before_it_writes() {
    let out = empty_dir!("run-locked");
    let held = FolderLock::take(&out).unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/scenes/dimer.toml");
    let run = || {
        let mut c = Command::new(BIN);
        c.arg("run")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap()
    };
    let o = run();
    let said = text(&o);
    assert_eq!(o.status.code(), Some(1), "{said}");
    assert!(
        said.contains("another process is writing this folder"),
        "{said}"
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0, "it wrote");
    drop(held);
    let o = run();
    assert!(o.status.success(), "{}", text(&o));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_locked_point_is_skipped_and_said_or_waited_for_with_wait() {
    let root = empty_dir!("held");
    let id = first_point();
    let point = root.join("points").join(&id);
    std::fs::create_dir_all(&point).unwrap();
    let held = FolderLock::take(&point).unwrap();
    let o = sweep(&root, &id).output().unwrap();
    let said = text(&o);
    assert!(o.status.success(), "{said}");
    assert!(
        said.contains(": skipped: locked by another process")
            && said.contains(", 1 skipped: locked by another process"),
        "{said}"
    );
    assert_eq!(std::fs::read_dir(&point).unwrap().count(), 0, "it wrote");
    let mut waiting = sweep(&root, &id)
        .arg("--wait")
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(waiting.try_wait().unwrap().is_none(), "it did not wait");
    assert_eq!(std::fs::read_dir(&point).unwrap().count(), 0, "it wrote");
    drop(held);
    let o = waiting.wait_with_output().unwrap();
    let said = text(&o);
    assert!(o.status.success(), "{said}");
    assert!(
        said.contains(&format!("{id}: locked by another process: waiting for it"))
            && said.contains(": ran, "),
        "{said}"
    );
    assert!(point.join("summary.json").is_file());
    let _ = std::fs::remove_dir_all(&root);
}

/// Flips one byte of `path`, a third of the way in.
fn flip_a_byte(path: &Path) {
    let mut bytes = std::fs::read(path).unwrap();
    let k = bytes.len() / 3;
    bytes[k] ^= 0x01;
    std::fs::write(path, bytes).unwrap();
}

/// A finished point whose data file was damaged in place (a byte flipped, or another
/// point's file of the same size copied over it) is collected corrupt, and the next
/// run recomputes it from the start: its files come out byte for byte as a clean
/// run's, and `collect` then reports it done.
#[test]
fn a_damaged_finished_point_runs_again_from_the_start() {
    let root = empty_dir!("damaged");
    let clean = root.join("clean");
    let o = Command::new(BIN)
        .arg("sweep")
        .arg(small())
        .arg("--out")
        .arg(&clean)
        .args(["--jobs", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let id = first_point();
    let clean_point = clean.join("points").join(&id);
    // Another point whose GSD has the same size (the same steps and particles).
    let size = |p: &Path| std::fs::metadata(p).unwrap().len();
    let gsd = clean_point.join("trajectory.gsd");
    let twin = std::fs::read_dir(clean.join("points"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p != &clean_point && size(&p.join("trajectory.gsd")) == size(&gsd))
        .expect("two points with GSD files of one size");
    // The file damaged, and how: a byte flipped, or the twin's file copied over it.
    let damages = [
        ("trajectory.gsd", false),
        ("trajectory.xyz", false),
        ("observables.csv", false),
        ("trajectory.gsd", true),
    ];
    for (k, &(name, copied)) in damages.iter().enumerate() {
        let out = root.join(format!("try-{k}"));
        let o = sweep(&out, &id).output().unwrap();
        assert!(o.status.success(), "{}", text(&o));
        let point = out.join("points").join(&id);
        let file = point.join(name);
        if copied {
            std::fs::copy(twin.join(name), &file).unwrap();
        } else {
            flip_a_byte(&file);
        }
        assert!(
            std::fs::read(&file).unwrap() != std::fs::read(clean_point.join(name)).unwrap(),
            "try {k}: {name} not damaged"
        );
        let (_, said) = collect(&out);
        let line = said.lines().find(|l| l.starts_with(&id)).unwrap();
        assert!(line.contains(" corrupt "), "try {k}: {line}");
        let o = sweep(&out, &id).output().unwrap();
        let said = text(&o);
        assert!(o.status.success(), "try {k}: {said}");
        assert!(
            said.contains(": ran, ") && said.contains("(1 from the start, 0 resumed"),
            "try {k}: not run from the start: {said}"
        );
        for name in DATA {
            let (x, y) = (
                std::fs::read(clean_point.join(name)).unwrap(),
                std::fs::read(point.join(name)).unwrap(),
            );
            assert!(x == y, "try {k}: {name} differs from a clean run's");
        }
        assert_eq!(summary(&clean_point), summary(&point), "try {k}");
        let (_, said) = collect(&out);
        assert!(!said.contains(&id), "try {k}: {id} not done: {said}");
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// `collect` while a job runs a point (a live process holds its lock): the point is
/// `running`, not unfinished, and the `sbatch` line to run again leaves its task out.
#[test]
fn collect_reports_a_locked_point_running_not_to_be_resubmitted() {
    let root = empty_dir!("running");
    let o = Command::new(BIN)
        .arg("sweep")
        .arg(small())
        .arg("--out")
        .arg(&root)
        .args(["--emit", "slurm"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let id = first_point();
    let held = FolderLock::take(&root.join("points").join(&id)).unwrap();
    let (ok, said) = collect(&root);
    assert!(!ok, "{said}");
    let line = said.lines().find(|l| l.starts_with(&id)).unwrap();
    assert!(line.contains(" running "), "{line}");
    // The first point is task 0 of 8 (one per point): the others run again.
    assert!(
        said.contains("7 points to run again: sbatch --array=1-7 ")
            && said.contains("1 points running now"),
        "{said}"
    );
    let table = std::fs::read_to_string(root.join("collected.csv")).unwrap();
    let row = table.lines().find(|l| l.starts_with(&id)).unwrap();
    assert!(row.contains(",running,"), "{row}");
    drop(held);
    let (_, said) = collect(&root);
    let line = said.lines().find(|l| l.starts_with(&id)).unwrap();
    assert!(line.contains(" missing "), "{line}");
    let _ = std::fs::remove_dir_all(&root);
}
