//! No import circles between the host library's modules (issue 28): each top-level
//! module (one concern: `scene`, `sim`, `output`, `sweep`, ...) may use others only in
//! one direction. Read from the source, as anyone can check with an import grep:
//! `grep -rhoE 'crate::[a-z_]+' host/src/<module>`. The study crate is checked the same
//! way, and neither library may name a CLI, terminal or plotting crate in the host.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a file belongs to (`scene` for `src/scene/resolve.rs`).
fn module(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// `module -> the other modules its files name as crate::X`.
fn graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    sources(src, &mut files);
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let m = module(src, &f);
        // Code only: a doc comment's link is not an import.
        let text: String = std::fs::read_to_string(&f)
            .unwrap()
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let deps = g.entry(m.clone()).or_default();
        for (i, _) in text.match_indices("crate::") {
            let name: String = text[i + 7..]
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_')
                .collect();
            if !name.is_empty() && name != m {
                deps.insert(name);
            }
        }
    }
    g
}

/// A cycle through `start`, if any (depth-first).
fn cycle(g: &BTreeMap<String, BTreeSet<String>>, path: &mut Vec<String>) -> Option<Vec<String>> {
    let last = path.last().unwrap().clone();
    for next in g.get(&last).into_iter().flatten() {
        if next == &path[0] {
            let mut c = path.clone();
            c.push(next.clone());
            return Some(c);
        }
        if !path.contains(next) && g.contains_key(next) {
            path.push(next.clone());
            if let Some(c) = cycle(g, path) {
                return Some(c);
            }
            path.pop();
        }
    }
    None
}

fn assert_acyclic(src: &Path) {
    let g = graph(src);
    let cycles: Vec<String> = g
        .keys()
        .filter(|m| m.as_str() != "lib")
        .filter_map(|m| cycle(&g, &mut vec![m.clone()]))
        .map(|c| c.join(" -> "))
        .collect();
    assert!(
        cycles.is_empty(),
        "import circles in {}: {cycles:#?}",
        src.display()
    );
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

#[test]
fn the_host_library_has_no_import_circles() {
    assert_acyclic(&root().join("host/src"));
}

#[test]
fn the_study_has_no_import_circles() {
    assert_acyclic(&root().join("study/src"));
}

#[test]
fn the_host_library_names_no_cli_terminal_or_plotting_crate() {
    let manifest = std::fs::read_to_string(root().join("host/Cargo.toml")).unwrap();
    for name in [
        "clap",
        "indicatif",
        "plotters",
        "gif",
        "env_logger",
        "ab_glyph",
    ] {
        let named = manifest
            .lines()
            .any(|l| l.split('=').next().unwrap().trim() == name);
        assert!(!named, "host/Cargo.toml depends on {name}");
    }
    let mut files = Vec::new();
    sources(&root().join("host/src"), &mut files);
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for name in ["clap::", "indicatif::", "plotters::", "gif::"] {
            assert!(!text.contains(name), "{} uses {name}", f.display());
        }
    }
}

/// The checker finds a circle where there is one.
#[test]
fn a_circle_is_found() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.insert("a".into(), ["b".to_string()].into());
    g.insert("b".into(), ["c".to_string()].into());
    g.insert("c".into(), ["a".to_string()].into());
    let c = cycle(&g, &mut vec!["a".to_string()]).unwrap();
    assert_eq!(c, ["a", "b", "c", "a"]);
}
