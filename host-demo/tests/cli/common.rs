//! Helpers shared by the command line's tests.

use std::path::PathBuf;
use std::process::{Command, Output};

/// The command line under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_host-demo");

/// The files a resumed run writes to the bytes of one run.
pub const SAME: [&str; 4] = [
    "trajectory.xyz",
    "trajectory.gsd",
    "observables.csv",
    "scene.toml",
];

/// The package's folder: its scenes, sweeps and test data.
pub fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The scratch folder `name` of the test file `module` (a `module_path!()`), removed:
/// the file's name prefixes the folder, so no two files of the one binary share one
/// (`scratch!` and `empty_dir!` in `main.rs` pass the caller's module).
pub fn scratch(module: &str, name: &str) -> PathBuf {
    let file = module.rsplit("::").next().unwrap_or(module);
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{file}-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// [`scratch`], made again: an empty folder.
pub fn empty_dir(module: &str, name: &str) -> PathBuf {
    let d = scratch(module, name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// What `host-demo ARGS` wrote to stdout and stderr, in that order.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Runs `host-demo ARGS`.
pub fn cli(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .output()
        .expect("host-demo runs")
}

/// Runs `host-demo ARGS`, which must succeed; what it wrote.
pub fn ok(args: &[&str]) -> String {
    let o = cli(args);
    assert!(o.status.success(), "{args:?}: {}", text(&o));
    text(&o)
}
