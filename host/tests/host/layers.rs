//! No import circles between the host library's modules: each top-level
//! module (one concern: `scene`, `sim`, `output`, `sweep`, ...) may use others only in
//! one direction. Read from the source, as anyone can check with an import grep:
//! `grep -rhoE 'crate::[a-z_]+' host/src/<module>`. The study crate is checked the same
//! way, and neither library may name a CLI, terminal or plotting crate in the host.
//!
//! The kernel (`../src`) is checked the same way and, further, against its declared
//! layers ([`KERNEL_LAYERS`], as `src/lib.rs` documents them): a module names only
//! modules of its own layer or below.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
pub(super) fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
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

/// `module -> the other modules its files name as crate::X`, `crate::{X, Y}` or a
/// `super::` path that reaches the crate root.
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
        let rel = f.strip_prefix(src).unwrap();
        let depth = rel.components().count() - usize::from(rel.ends_with("mod.rs"));
        let deps = g.entry(m.clone()).or_default();
        deps.extend(imports(&text, depth).into_iter().filter(|d| *d != m));
    }
    let known: BTreeSet<String> = g.keys().cloned().collect();
    for deps in g.values_mut() {
        deps.retain(|d| known.contains(d));
    }
    g
}

/// The top-level modules `text`, the code of a file `depth` modules deep (`src/a/b.rs`:
/// 2, `src/a/mod.rs`: 1), names: `crate::X`, `crate::{X, Y::{..}}`, and `super::X`
/// where the `super::`s reach the crate root. Inline modules (`mod tests`) are deeper
/// still, so this may take a sibling for a top-level module: [`graph`] keeps only names
/// of top-level modules.
fn imports(text: &str, depth: usize) -> Vec<String> {
    let mut names = Vec::new();
    for (i, _) in text.match_indices("crate::") {
        let rest = &text[i + 7..];
        match rest.strip_prefix('{') {
            Some(list) => names.extend(braced(list)),
            None => names.push(ident(rest)),
        }
    }
    for (i, _) in text.match_indices("super::") {
        if text[..i].ends_with("super::") {
            continue;
        }
        let mut rest = &text[i..];
        let mut k = 0;
        while let Some(r) = rest.strip_prefix("super::") {
            rest = r;
            k += 1;
        }
        if k == depth {
            names.push(ident(rest));
        }
    }
    names.retain(|n| !n.is_empty());
    names
}

/// The module name at the start of `s`.
pub(super) fn ident(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_')
        .collect()
}

/// The first name of each entry of a `use` list (`a, b::{c, d}, e}` gives a, b, e).
pub(super) fn braced(list: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut depth = 0;
    let mut start = true;
    for (i, c) in list.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => start = true,
            c if start && !c.is_whitespace() => {
                names.push(ident(&list[i..]));
                start = false;
            }
            _ => {}
        }
    }
    names
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

pub(super) fn root() -> PathBuf {
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

/// The kernel's layers, bottom first, as `src/lib.rs` declares them: a module may name
/// modules of its own layer or below, never above.
const KERNEL_LAYERS: &[(&str, &[&str])] = &[
    ("foundation", &["real", "fault", "helix"]),
    ("linear algebra", &["linalg"]),
    (
        "free-space pairs, the periodic cell, the near field's pair functions",
        &["rpy", "cell", "near"],
    ),
    (
        "bonds, cell lists and bands",
        &["bonds", "cell_list", "parallel"],
    ),
    ("noise", &["noise"]),
    (
        "the geometries' mobility, particles",
        &["mobility", "particles", "observables"],
    ),
    ("the step's error", &["error", "error_info"]),
    (
        "the geometry a step sees, the dense Stokesian dynamics mobility",
        &["geometry", "stokesian"],
    ),
    ("constraints", &["constraints"]),
    ("configuration", &["params", "forces", "names"]),
    ("workspace", &["workspace"]),
    ("integrators", &["integrate"]),
];

/// `(module, layer, import, its layer)` for every import of a module from a higher
/// layer; a module missing from the table is an error of its own.
fn upward(
    g: &BTreeMap<String, BTreeSet<String>>,
    layers: &[(&str, &[&str])],
) -> Result<Vec<String>, String> {
    let layer = |m: &str| layers.iter().position(|(_, ms)| ms.contains(&m));
    let mut up = Vec::new();
    for (m, deps) in g.iter().filter(|(m, _)| m.as_str() != "lib") {
        let Some(lm) = layer(m) else {
            return Err(format!("module {m} is in no layer"));
        };
        for d in deps {
            let ld = layer(d).ok_or_else(|| format!("module {d} is in no layer"))?;
            if ld > lm {
                up.push(format!("{m} ({}) -> {d} ({})", layers[lm].0, layers[ld].0));
            }
        }
    }
    Ok(up)
}

#[test]
fn the_kernel_has_no_import_circles() {
    assert_acyclic(&root().join("src"));
}

#[test]
fn the_kernel_imports_only_its_own_layer_or_below() {
    let g = graph(&root().join("src"));
    let up = upward(&g, KERNEL_LAYERS).unwrap();
    assert!(up.is_empty(), "upward imports in the kernel: {up:#?}");
}

/// Prints the kernel's import graph, a module a line with the modules it names:
/// `cargo test --release -p hydrorattle-host --test host import_graph -- --nocapture`.
#[test]
fn the_kernel_import_graph() {
    let g = graph(&root().join("src"));
    for (m, deps) in g.iter().filter(|(m, _)| m.as_str() != "lib") {
        let deps: Vec<&str> = deps.iter().map(String::as_str).collect();
        println!("{m} -> {}", deps.join(", "));
    }
    assert!(g.len() > 10, "{g:?}");
}

/// Every way a file names a top-level module is read: a path, a `use` list (its
/// entries' first names only), and `super::` as far as the crate root, not short of it.
#[test]
fn every_form_of_import_is_read() {
    let text =
        "use crate::a::X;\nuse crate::{b, c::{d, e::F}, g};\nsuper::super::h::f();\nsuper::i();";
    assert_eq!(imports(text, 2), ["a", "b", "c", "g", "h"]);
    assert_eq!(imports(text, 1), ["a", "b", "c", "g", "i"]);
}

/// An import from a higher layer is found, and so is a module the table misses.
#[test]
fn an_upward_import_is_found() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.insert("low".into(), ["high".to_string()].into());
    g.insert("high".into(), BTreeSet::new());
    let layers: &[(&str, &[&str])] = &[("bottom", &["low"]), ("top", &["high"])];
    assert_eq!(upward(&g, layers).unwrap(), ["low (bottom) -> high (top)"]);
    g.insert("new".into(), BTreeSet::new());
    assert!(upward(&g, layers).is_err());
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
