//! The repository's documents point only at what the repository holds (issue 28, item
//! 5): every `*.md` path named in a source, scene, script or document of the
//! repository exists inside it, and every `#anchor` attached to such a path (or to a
//! markdown link within one document) is a heading of the document it names, by
//! GitHub's slug rules. One test walks the working tree and lists every broken
//! reference at once.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Component, Path, PathBuf};

/// The kinds of file whose text is read.
const EXTENSIONS: &[&str] = &["rs", "md", "toml", "py", "sh", "c", "h"];

/// Folders never read: build outputs, run outputs, version control, caches and
/// virtual environments (none of them is part of the repository's text).
const SKIP: &[&str] = &[
    "target",
    ".git",
    "out",
    "__pycache__",
    ".hypothesis",
    ".pytest_cache",
    ".venv",
    "venv",
    "node_modules",
    "site-packages",
];

fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file to read below `dir`, in a fixed order.
fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            if !SKIP.contains(&name.as_str()) {
                walk(&path, out);
            }
            continue;
        }
        let ext = path.extension().map(|e| e.to_string_lossy().into_owned());
        // `.ci/run` is a bash script without an extension.
        let in_ci = path
            .parent()
            .and_then(|p| p.file_name())
            .is_some_and(|p| p == ".ci");
        if ext.is_some_and(|e| EXTENSIONS.contains(&e.as_str())) || in_ci {
            out.push(path);
        }
    }
}

/// `path` with `.` and `..` folded away lexically; `None` when it climbs above its
/// start.
fn normalise(path: &Path) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::Normal(p) => out.push(p),
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    Some(out)
}

fn is_path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/')
}

fn is_anchor_char(c: char) -> bool {
    c.is_alphanumeric() || matches!(c, '_' | '-')
}

/// One reference found in a line: the path as written and the anchor after it.
struct Reference {
    path: String,
    anchor: Option<String>,
}

/// The `*.md` paths named in `line`: runs of path characters ending in `.md` (not
/// `.mdx` and the like), with an optional `#anchor` right after. URLs (`//`), globs
/// (`*.md`: the run is then `.md` alone) and hidden names are not references.
fn references(line: &str) -> Vec<Reference> {
    let chars: Vec<char> = line.chars().collect();
    let mut found = Vec::new();
    let mut i = 0;
    while i + 3 <= chars.len() {
        let is_md = chars[i] == '.' && chars[i + 1] == 'm' && chars[i + 2] == 'd';
        let after = chars.get(i + 3).copied();
        if !is_md || after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') {
            i += 1;
            continue;
        }
        let end = i + 3;
        let mut start = i;
        while start > 0 && is_path_char(chars[start - 1]) {
            start -= 1;
        }
        let path: String = chars[start..end].iter().collect();
        let name = path.rsplit('/').next().unwrap_or("");
        let url = path.contains("//") || (start > 0 && chars[start - 1] == ':');
        if !url && !name.starts_with('.') && name.len() > 3 {
            let mut anchor = None;
            if after == Some('#') {
                let mut j = end + 1;
                while j < chars.len() && is_anchor_char(chars[j]) {
                    j += 1;
                }
                anchor = Some(chars[end + 1..j].iter().collect());
            }
            found.push(Reference { path, anchor });
        }
        i = end;
    }
    found
}

/// Same-document links of a markdown line: `](#anchor)`.
fn local_anchors(line: &str) -> Vec<String> {
    line.match_indices("](#")
        .map(|(k, m)| {
            line[k + m.len()..]
                .chars()
                .take_while(|&c| is_anchor_char(c))
                .collect()
        })
        .collect()
}

/// GitHub's anchor for a heading: lower case, spaces to hyphens, every character that
/// is not a letter, digit, `_` or `-` dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '_' || c == '-' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a markdown document: its headings outside fenced code, repeated
/// slugs numbered `-1`, `-2`, ... as GitHub does.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut fence = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("```") || t.starts_with("~~~") {
            fence = !fence;
            continue;
        }
        if fence || !line.starts_with('#') {
            continue;
        }
        let level = line.chars().take_while(|&c| c == '#').count();
        let rest = &line[level..];
        if level > 6 || !rest.starts_with(' ') {
            continue;
        }
        let base = slug(rest.trim().trim_end_matches('#'));
        let mut s = base.clone();
        let mut k = 0;
        while seen.contains(&s) {
            k += 1;
            s = format!("{base}-{k}");
        }
        seen.insert(s);
    }
    seen
}

#[test]
fn every_referenced_md_exists_and_every_anchor_is_a_heading() {
    let root = repo_root();
    let mut files = Vec::new();
    walk(&root, &mut files);
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in &files {
        let Ok(text) = fs::read_to_string(file) else {
            continue;
        };
        let rel = file.strip_prefix(&root).unwrap();
        let dir = rel.parent().unwrap_or(Path::new(""));
        let is_md = rel.extension().is_some_and(|e| e == "md");
        for (n, line) in text.lines().enumerate() {
            let at = format!("{}:{}", rel.display(), n + 1);
            for r in references(line) {
                checked += 1;
                // Relative to the naming file, then to the repository root.
                let target = [dir.join(&r.path), PathBuf::from(&r.path)]
                    .into_iter()
                    .filter_map(|p| normalise(&p))
                    .find(|p| root.join(p).is_file());
                let Some(target) = target else {
                    problems.push(format!(
                        "{at}: `{}` is not a file of the repository",
                        r.path
                    ));
                    continue;
                };
                if let Some(a) = r.anchor.filter(|a| !a.is_empty()) {
                    let heads = anchors(&fs::read_to_string(root.join(&target)).unwrap());
                    if !heads.contains(&a) {
                        problems.push(format!(
                            "{at}: `{}#{a}`: no such heading in {}",
                            r.path,
                            target.display()
                        ));
                    }
                }
            }
            if is_md {
                for a in local_anchors(line) {
                    checked += 1;
                    if !anchors(&text).contains(&a) {
                        problems.push(format!("{at}: `#{a}`: no such heading in this file"));
                    }
                }
            }
        }
    }
    assert!(
        checked > 50,
        "only {checked} references found: is the walk broken?"
    );
    assert!(
        problems.is_empty(),
        "{} broken references to markdown files:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn slugs_follow_github() {
    assert_eq!(
        slug("Python (`import hydrorattle`)"),
        "python-import-hydrorattle"
    );
    assert_eq!(slug("Figure 1 at dt = 0.1"), "figure-1-at-dt--01");
    assert_eq!(
        slug("Speed against accuracy (`host-demo chart`)"),
        "speed-against-accuracy-host-demo-chart"
    );
    let a = anchors("# A\n```\n# not a heading\n```\n## A\n#hashtag\n");
    assert_eq!(a.into_iter().collect::<Vec<_>>(), ["a", "a-1"]);
    let r = references("see [x](../docs/MODEL.md#units), `*.md` and https://x.org/y.md");
    assert_eq!(r.len(), 1);
    assert_eq!(
        (r[0].path.as_str(), r[0].anchor.as_deref()),
        ("../docs/MODEL.md", Some("units"))
    );
    assert_eq!(normalise(Path::new("tests/../../x")), None);
}
