//! Records the code version at build time: `git describe` of the checkout, or the
//! crate version when there is no git (a source archive).
//!
//! The commit is abbreviated to a fixed 12 digits: git's automatic length grows with
//! the number of objects in the repository, so two builds of one commit (the CLI's and
//! the Python package's, a few minutes apart) could otherwise name it differently.

use std::process::Command;

fn main() {
    let described = git(&["describe", "--always", "--abbrev=12", "--dirty", "--tags"]);
    let version = match described {
        Some(d) => format!("{} ({d})", env!("CARGO_PKG_VERSION")),
        None => format!("{} (no git)", env!("CARGO_PKG_VERSION")),
    };
    println!("cargo:rustc-env=HYDRORATTLE_HOST_VERSION={version}");
    // Rebuilt when the checked-out commit or the index changes (the paths asked of git,
    // so that a linked worktree works too).
    let head_ref = git(&["rev-parse", "--symbolic-full-name", "HEAD"]);
    let mut watched = vec!["HEAD".to_string(), "index".to_string()];
    watched.extend(head_ref.filter(|r| r.starts_with("refs/")));
    for name in watched {
        if let Some(path) = git(&["rev-parse", "--git-path", &name])
            && std::path::Path::new(&path).exists()
        {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    println!("cargo:rerun-if-changed=build.rs");
}

/// The trimmed output of a successful `git` command.
fn git(args: &[&str]) -> Option<String> {
    Command::new("git")
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
}
