//! The repository's documents point only at what the repository holds: every `*.md`
//! path named in a source, scene, script or document of the repository exists inside
//! it, every `#anchor` attached to such a path (or to a markdown link within one
//! document) is a heading of the document it names, by GitHub's slug rules, and every
//! repository path a markdown document names (in backticks, a link or a code block:
//! `src/real.rs`, `host/src/scene/`, `examples/peak`) is a file or folder of the
//! repository; every benchmark record in `bench/results/` names its commit, machine,
//! command and value. The tests walk the working tree and list every problem at once.

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

/// The words of a markdown line that may name a path: inside backticks and link
/// targets in prose, every word in a fenced code block (`in_code`), each with its
/// surrounding quotes, brackets and punctuation, a `#anchor` and a `:line` removed.
fn words(line: &str, in_code: bool) -> Vec<&str> {
    let mut raw: Vec<&str> = Vec::new();
    if in_code {
        raw.extend(line.split_whitespace());
    } else {
        raw.extend(
            line.split('`')
                .skip(1)
                .step_by(2)
                .flat_map(str::split_whitespace),
        );
        for (k, m) in line.match_indices("](") {
            let rest = &line[k + m.len()..];
            raw.push(&rest[..rest.find([')', ' ']).unwrap_or(rest.len())]);
        }
    }
    raw.into_iter()
        .filter(|w| !w.contains("://"))
        .map(|w| {
            let w = w.trim_start_matches(['"', '\'', '(', '[', '<']);
            let w = &w[..w.find(['#', ':']).unwrap_or(w.len())];
            let w = w.trim_end_matches(['"', '\'', ')', ']', '>', ',', ';', '!', '?']);
            if w.ends_with("/...") {
                w
            } else {
                w.trim_end_matches('.')
            }
        })
        .collect()
}

/// `word` as a path into the repository, when it reads as one: path characters only,
/// at least one `/`, relative, starting at `.`, `..`, a top-level folder of the
/// repository (`tops`) or a folder beside the document (in `dir`), and not inside a
/// build output (`target`, `target-v3`). A trailing `/...` ("and so on") names the
/// folder.
fn repo_path(word: &str, tops: &BTreeSet<String>, root: &Path, dir: &Path) -> Option<String> {
    let word = word.strip_suffix("...").unwrap_or(word);
    if !word.contains('/') || word.starts_with('/') || !word.chars().all(is_path_char) {
        return None;
    }
    let mut parts = word.split('/');
    let first = parts.next().unwrap_or("");
    let here = matches!(first, "." | "..") || tops.contains(first);
    if !here && !root.join(dir).join(first).is_dir() {
        return None;
    }
    if word
        .split('/')
        .any(|p| p == "target" || p.starts_with("target-"))
    {
        return None;
    }
    Some(word.to_string())
}

/// `path`, named in a document in folder `dir`, resolved relative to that folder, then
/// to the repository root: a file, a folder, or an example or binary named without
/// its `.rs`.
fn resolves(root: &Path, dir: &Path, path: &str) -> bool {
    [dir.join(path), PathBuf::from(path)]
        .into_iter()
        .filter_map(|p| normalise(&p))
        .any(|p| {
            let p = root.join(p);
            p.exists() || p.with_extension("rs").is_file()
        })
}

#[test]
fn every_path_a_document_names_exists() {
    let root = repo_root();
    let mut files = Vec::new();
    walk(&root, &mut files);
    let tops: BTreeSet<String> = fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !SKIP.contains(&n.as_str()))
        .collect();
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "md"))
    {
        let text = fs::read_to_string(file).unwrap();
        let rel = file.strip_prefix(&root).unwrap();
        let dir = rel.parent().unwrap_or(Path::new(""));
        let mut in_code = false;
        for (n, line) in text.lines().enumerate() {
            let t = line.trim_start();
            if t.starts_with("```") || t.starts_with("~~~") {
                in_code = !in_code;
                continue;
            }
            for w in words(line, in_code) {
                // A command's or a user's file's `./x` and `../x` are relative to where
                // it runs, which the document does not fix.
                if in_code && (w.starts_with("./") || w.starts_with("../")) {
                    continue;
                }
                let Some(path) = repo_path(w, &tops, &root, dir) else {
                    continue;
                };
                checked += 1;
                if !resolves(&root, dir, &path) {
                    problems.push(format!(
                        "{}:{}: `{path}` is not in the repository",
                        rel.display(),
                        n + 1
                    ));
                }
            }
        }
    }
    assert!(
        checked > 200,
        "only {checked} paths found: is the scan broken?"
    );
    assert!(
        problems.is_empty(),
        "{} paths named in documents that the repository lacks:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// The fields of one CSV line (RFC 4180: quoted fields may hold commas and `""`).
fn csv_fields(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                fields.last_mut().unwrap().push('"');
            }
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(String::new()),
            c => fields.last_mut().unwrap().push(c),
        }
    }
    fields
}

/// Every benchmark record names what docs/BENCHMARKS.md promises: the commit, a
/// machine of its "Machines" table, the command, and the value.
#[test]
fn every_benchmark_record_is_complete() {
    let root = repo_root();
    let page = fs::read_to_string(root.join("docs/BENCHMARKS.md")).unwrap();
    let mut records = 0;
    let mut problems = Vec::new();
    let mut files: Vec<_> = fs::read_dir(root.join("bench/results"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    for file in &files {
        let text = fs::read_to_string(file).unwrap();
        let mut lines = text.lines();
        let header = csv_fields(lines.next().unwrap_or(""));
        let column = |name: &str| header.iter().position(|h| h == name);
        let [Some(commit), Some(machine), Some(command), Some(value)] =
            ["commit", "machine", "command", "value"].map(column)
        else {
            problems.push(format!("{}: header {header:?}", file.display()));
            continue;
        };
        for (n, line) in lines.enumerate() {
            records += 1;
            let f = csv_fields(line);
            let at = format!("{}:{}", file.display(), n + 2);
            let hex = f[commit].len() >= 7 && f[commit].chars().all(|c| c.is_ascii_hexdigit());
            // A timing record may give its value in a `seconds` column instead.
            let timed = column("seconds").is_some_and(|k| f.get(k).is_some_and(|s| !s.is_empty()));
            let valued = f.get(value).is_some_and(|v| !v.is_empty()) || timed;
            if f.len() != header.len() || !hex || f[command].is_empty() || !valued {
                problems.push(format!("{at}: incomplete record {f:?}"));
            } else if !page.contains(&format!("| `{}` |", f[machine])) {
                problems.push(format!(
                    "{at}: machine `{}` is not in docs/BENCHMARKS.md",
                    f[machine]
                ));
            }
        }
    }
    assert!(records > 100, "only {records} benchmark records found");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn words_and_paths() {
    let line = "see `src/real.rs:12`, [x](../host/src/lib.rs#L3), `cargo run -p host-demo`";
    assert_eq!(
        words(line, false),
        [
            "src/real.rs",
            "cargo",
            "run",
            "-p",
            "host-demo",
            "../host/src/lib.rs"
        ]
    );
    assert_eq!(
        words("bash .ci/run; ls host/src/...", true),
        ["bash", ".ci/run", "ls", "host/src/..."]
    );
    let root = repo_root();
    let tops: BTreeSet<String> = ["src", "host"].map(String::from).into();
    let here = Path::new("docs");
    let path = |w| repo_path(w, &tops, &root, here);
    assert_eq!(path("host/src/..."), Some("host/src/".into()));
    assert_eq!(path("../src/x.rs"), Some("../src/x.rs".into()));
    // Not repository paths: no folder, an absolute path, a placeholder folder, a glob,
    // a build output.
    for w in [
        "real.rs",
        "/usr/lib",
        "DIR/slurm.sh",
        "src/*.rs",
        "src/target/x",
    ] {
        assert_eq!(path(w), None, "{w}");
    }
    assert!(resolves(&root, here, "../src/real.rs"));
    assert!(resolves(&root, here, "src/real.rs"));
    assert!(resolves(&root, here, "examples/peak"));
    assert!(!resolves(&root, here, "src/auto.rs"));
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
    let r = references("see [x](../../docs/MODEL.md#units), `*.md` and https://x.org/y.md");
    assert_eq!(r.len(), 1);
    assert_eq!(
        (r[0].path.as_str(), r[0].anchor.as_deref()),
        ("../../docs/MODEL.md", Some("units"))
    );
    assert_eq!(normalise(Path::new("tests/../../x")), None);
    assert_eq!(
        csv_fields(r#"a,"b, c","say ""hi""",,"#),
        ["a", "b, c", r#"say "hi""#, "", ""]
    );
}
