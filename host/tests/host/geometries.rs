//! Each geometry's hydrodynamics lives in its own modules behind the kernel's one
//! interface (`src/geometry.rs`: the trait `Geometry`, the enum `Hydrodynamics` and the
//! registration `geometries!`): the registration file forwards and never implements,
//! and no file outside a geometry's modules names them, except those listed below,
//! which a new geometry does not touch. Read from the source, as `layers.rs` reads
//! the imports.

use std::collections::BTreeSet;

use super::layers::{braced, ident, root, sources};

/// The code of `text`: comment lines dropped (a doc's link names no code).
fn code(text: &str) -> String {
    let lines = text.lines().filter(|l| !l.trim_start().starts_with("//"));
    lines.collect::<Vec<_>>().join("\n")
}

/// The lower-case names (modules, functions) `text` names after each `module::`: `a`
/// of `module::a::f`, and the first name of each entry of a list, `a` and `b` of
/// `module::{a, b::C}`; a type (`module::T`) gives an empty name.
fn named_in(text: &str, module: &str) -> Vec<String> {
    let pat = format!("{module}::");
    let mut names = Vec::new();
    for (i, _) in text.match_indices(&pat) {
        // `free_fast::` is not `fast::`.
        if text[..i].ends_with(|c: char| c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        let rest = &text[i + pat.len()..];
        match rest.strip_prefix('{') {
            Some(list) => names.extend(braced(list)),
            None => names.push(ident(rest)),
        }
    }
    names
}

/// A geometry: its name, the modules that implement it (under `crate::mobility` and
/// `crate::geometry`), and the files they are (paths under `src/`, a folder's prefix;
/// a geometry's part of the near field's Stokesian dynamics, `stokesian/wall.rs` and
/// `stokesian/periodic.rs`, included), and the geometries whose blocks it is built from
/// (the slit: the wall's image blocks, superposed), which its own files may name.
struct Geometry {
    name: &'static str,
    modules: &'static [&'static str],
    files: &'static [&'static str],
    builds_on: &'static [&'static str],
}

const GEOMETRIES: &[Geometry] = &[
    Geometry {
        name: "wall",
        modules: &["wall"],
        files: &["mobility/wall", "geometry/wall", "stokesian/wall.rs"],
        builds_on: &[],
    },
    Geometry {
        name: "periodic box",
        modules: &["periodic", "pse", "sums"],
        files: &[
            "mobility/periodic",
            "mobility/pse",
            "geometry/periodic",
            "geometry/sums.rs",
            "stokesian/periodic.rs",
        ],
        builds_on: &[],
    },
    Geometry {
        name: "slit",
        modules: &["slit"],
        files: &["mobility/slit", "geometry/slit", "integrate/checks/slit.rs"],
        builds_on: &["wall"],
    },
];

/// The files outside a geometry's own that still name its modules, `(file, geometry)`:
/// none. A file may leave this list, never join it, and every file listed still names
/// the geometry (the list is exact).
const STILL_NAMED: &[(&str, &str)] = &[];

/// Every kernel file: its path under `src/` and its text.
fn kernel_files() -> Vec<(String, String)> {
    let src = root().join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let rel = |f: &std::path::Path| {
        f.strip_prefix(&src)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/")
    };
    let text = |f: &std::path::Path| std::fs::read_to_string(f).unwrap();
    files.iter().map(|f| (rel(f), text(f))).collect()
}

/// `(file, geometry)` for every kernel file outside a geometry's own files that names
/// one of its modules through `crate::mobility` or `crate::geometry`.
fn naming() -> BTreeSet<(String, &'static str)> {
    let mut found = BTreeSet::new();
    for (rel, text) in kernel_files() {
        let text = code(&text);
        let mut names = named_in(&text, "mobility");
        names.extend(named_in(&text, "geometry"));
        for g in GEOMETRIES {
            let own = GEOMETRIES.iter().any(|h| {
                (h.name == g.name || h.builds_on.contains(&g.name))
                    && h.files.iter().any(|o| rel.starts_with(o))
            });
            if !own && g.modules.iter().any(|m| names.iter().any(|n| n == m)) {
                found.insert((rel.clone(), g.name));
            }
        }
    }
    found
}

/// The geometries the registration lists (`geometries!` in `src/geometry.rs`): the
/// name of each variant, the fallback after `_ =>` included.
fn registered(text: &str) -> Vec<String> {
    let start = text.find("geometries! {").expect("the registration");
    let body = &text[start..];
    let body = &body[..body.find("\n}").expect("the registration's end")];
    body.lines()
        .skip(1)
        .map(str::trim)
        .filter(|l| !l.starts_with('#') && !l.starts_with("//") && !l.starts_with("_ =>"))
        .filter_map(|l| l.split_once('(').map(|(v, _)| v.to_string()))
        .collect()
}

/// The registration file forwards every call to the geometry's own module: it names
/// no variant outside the registration (no `match` written by hand), and no function
/// or module of the modules a geometry implements itself with (`mobility`, `parallel`,
/// `noise`), only the types its signatures need.
#[test]
fn the_registration_file_forwards_and_never_implements() {
    let text = std::fs::read_to_string(root().join("src/geometry.rs")).unwrap();
    let variants = registered(&text);
    assert!(variants.len() >= 2, "{variants:?}");
    let body = non_test_code(&text);
    for v in &variants {
        for pat in [format!("Self::{v}"), format!("Hydrodynamics::{v}")] {
            assert!(
                !body.contains(&pat),
                "src/geometry.rs matches {pat} by hand"
            );
        }
    }
    for module in ["mobility", "parallel", "noise"] {
        for name in named_in(&body, module) {
            assert!(
                name.is_empty(),
                "src/geometry.rs names {module}::{name} (a geometry's own code)"
            );
        }
    }
}

/// The code of `text` before its unit tests (`#[cfg(test)] mod tests`), comments dropped.
fn non_test_code(text: &str) -> String {
    code(&text[..text.find("#[cfg(test)]\nmod tests").unwrap_or(text.len())])
}

/// Whether `text` names `pat` not followed by more of a name (`Place::Free`, not
/// `Place::FreeDraining`).
fn names_exactly(text: &str, pat: &str) -> bool {
    text.match_indices(pat).any(|(i, _)| {
        let after = text[i + pat.len()..].chars().next();
        !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
    })
}

/// The variants of `Place` and `Hydrodynamics` are the registration's: no kernel file
/// outside a geometry's own modules names one (`Place::Wall`, `Hydrodynamics::Free`),
/// and no `impl` of either matches one (`Self::Wall`). What a place answers, each
/// geometry answers in its own module; the rest forwards through the registration.
#[test]
fn no_variant_is_matched_outside_its_geometry() {
    let reg = std::fs::read_to_string(root().join("src/geometry.rs")).unwrap();
    let variants = registered(&reg);
    let own = |rel: &str| {
        rel.starts_with("geometry/free.rs")
            || GEOMETRIES
                .iter()
                .any(|g| g.files.iter().any(|o| rel.starts_with(o)))
    };
    let mut matched = Vec::new();
    for (rel, text) in kernel_files() {
        if own(&rel) {
            continue;
        }
        let text = non_test_code(&text);
        let implements = ["Place<", "Hydrodynamics<"]
            .iter()
            .any(|t| text.lines().any(|l| l.starts_with("impl") && l.contains(t)));
        for v in &variants {
            let mut pats = vec![format!("Place::{v}"), format!("Hydrodynamics::{v}")];
            if implements {
                pats.push(format!("Self::{v}"));
            }
            for pat in pats.iter().filter(|p| names_exactly(&text, p)) {
                matched.push(format!("src/{rel}: {pat}"));
            }
        }
    }
    assert!(matched.is_empty(), "variants matched by hand: {matched:?}");
}

/// The parameters' geometry fields (`Params::wall`, `Params::periodic`) are read in
/// `Params::place` alone: every other kernel file asks the place
/// (`p.place().wall()`, `.cell()`), which each geometry answers in its own module.
#[test]
fn the_geometry_fields_are_read_only_through_the_place() {
    let mut read = Vec::new();
    for (rel, text) in kernel_files() {
        if rel == "params.rs" || rel.starts_with("geometry") {
            continue;
        }
        let text = non_test_code(&text);
        for who in ["p", "params"] {
            for field in ["wall", "slit", "periodic"] {
                let pat = format!("{who}.{field}");
                let by_hand = text.match_indices(&pat).any(|(i, _)| {
                    let before = text[..i].chars().next_back();
                    let after = text[i + pat.len()..].chars().next();
                    !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.')
                        && !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '(')
                });
                if by_hand {
                    read.push(format!("src/{rel}: {pat}"));
                }
            }
        }
    }
    assert!(read.is_empty(), "geometry fields read by hand: {read:?}");
}

/// No file outside a geometry's own names its modules, but those [`STILL_NAMED`]
/// lists (printed: `cargo test --release -p hydrorattle-host --test host geometries::
/// -- --nocapture`).
#[test]
fn a_geometrys_modules_are_named_only_where_listed() {
    let found = naming();
    for (file, g) in &found {
        println!("src/{file}: {g}");
    }
    let listed: BTreeSet<(String, &str)> = STILL_NAMED
        .iter()
        .map(|&(f, g)| (f.to_string(), g))
        .collect();
    let extra: Vec<_> = found.difference(&listed).collect();
    assert!(extra.is_empty(), "named outside their geometry: {extra:?}");
    let stale: Vec<_> = listed.difference(&found).collect();
    assert!(
        stale.is_empty(),
        "listed but no longer named (drop from STILL_NAMED): {stale:?}"
    );
}

/// The reader sees a path, a `use` list, and not a longer name that ends alike.
#[test]
fn every_form_of_naming_is_read() {
    let text =
        "use crate::mobility::{Hydro, wall::{a, b}};\nmobility::periodic::f();\nfree_fast::g();";
    assert_eq!(named_in(text, "mobility"), ["", "wall", "periodic"]);
    assert!(named_in(text, "fast").is_empty());
    let reg = "geometries! {$\n    /// Doc.\n    #[cfg(feature = \"wall\")]\n    Wall(wall::Wall<T>),\n    _ =>\n    /// Free.\n    Free(free::Free<T>),\n}\n";
    assert_eq!(registered(reg), ["Wall", "Free"]);
    assert!(names_exactly("Place::Free(g)", "Place::Free"));
    assert!(!names_exactly("Hydro::FreeDraining", "Hydro::Free"));
}
