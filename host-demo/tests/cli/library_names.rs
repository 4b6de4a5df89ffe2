//! What a run writes names the library that wrote it (`hydrorattle-host` and its
//! version), not the command line; folders written under the command line's former
//! names are still resumed and collected.

use std::path::{Path, PathBuf};

use crate::common::ok;

use hydrorattle_host::provenance::APPLICATION;
use hydrorattle_host::sweep::record::{FORMAT, FORMERLY};

/// A two-point sweep of the shipped dimer, short, in `dir`.
fn dimer_sweep(dir: &Path) -> PathBuf {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/scenes/dimer.toml");
    let path = dir.join("sweep.toml");
    let text = format!(
        "[sweep]\nbase = {:?}\n\"integrator.duration\" = [1.0]\n\"integrator.dt\" = [0.1, 0.05]\n",
        base.display().to_string()
    );
    std::fs::write(&path, text).unwrap();
    path
}

fn sweep_json(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap()
}

#[test]
fn records_and_trajectories_name_the_library() {
    assert!(FORMAT.starts_with("hydrorattle-host "), "{FORMAT}");
    assert_eq!(
        APPLICATION,
        format!("hydrorattle-host {}", env!("CARGO_PKG_VERSION"))
    );
    let dir = empty_dir!("new");
    let out = dir.join("out");
    ok(&[
        "sweep",
        dimer_sweep(&dir).to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(sweep_json(&out)["format"], FORMAT);
    let points: Vec<PathBuf> = std::fs::read_dir(out.join("points"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(points.len(), 2);
    for point in points {
        let gsd = std::fs::read(point.join("trajectory.gsd")).unwrap();
        // GSD's header: the magic and four offsets and counts (8 bytes each), two
        // versions (4 each), then the application's name in 64 bytes.
        let application = &gsd[48..112];
        let name = &application[..application.iter().position(|&b| b == 0).unwrap()];
        assert_eq!(std::str::from_utf8(name).unwrap(), APPLICATION);
        assert!(!gsd.windows(9).any(|w| w == b"host-demo"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_sweep_recorded_under_a_former_name_resumes_and_collects() {
    for former in FORMERLY.iter().filter(|f| f.ends_with(" 2")) {
        let dir = empty_dir!("former");
        let (file, out) = (dimer_sweep(&dir), dir.join("out"));
        let (file_s, out_s) = (file.to_str().unwrap(), out.to_str().unwrap());
        ok(&["sweep", file_s, "--out", out_s, "--emit", "parallel"]);
        let ids = std::fs::read_to_string(out.join("point_ids.txt")).unwrap();
        let first = ids.lines().next().unwrap();
        ok(&["sweep", "--frozen", "--out", out_s, "--point", first]);
        // The folder as an earlier version recorded it: the same record, its old name.
        let mut record = sweep_json(&out);
        record["format"] = (*former).into();
        std::fs::write(
            out.join("sweep.json"),
            serde_json::to_string_pretty(&record).unwrap(),
        )
        .unwrap();
        // The sweep file goes on with it: one point done, the other runs.
        let said = ok(&["sweep", file_s, "--out", out_s]);
        assert!(said.contains("1 already finished"), "{said}");
        // Its frozen points and the collected table read it too.
        let said = ok(&["sweep", "--frozen", "--out", out_s]);
        assert!(said.contains("2 already finished"), "{said}");
        ok(&["collect", out_s]);
        let table = std::fs::read_to_string(out.join("collected.csv")).unwrap();
        assert_eq!(table.lines().count(), 3, "{table}");
        for id in ids.lines() {
            assert!(table.contains(id), "{id}: {table}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
