//! The base scene of a sweep and the scene of each point: the base's TOML table with
//! the point's values set at their dotted paths, resolved by the scene parser, and an
//! error placed at the sweep value that caused it (or else in the base scene).

use std::ops::Range;
use std::path::Path;

use toml::de::{DeTable, DeValue};
use toml::{Table, Value};

use super::file::{Source, at, describe, in_file_order};
use crate::scene::{Scene, SceneError, line_col};
use crate::sizing::Limits;

/// Sets the value at a dotted path (numbers index arrays, as `particle.1.radius`);
/// tables on the way are made when missing.
pub(super) fn set_path(table: &mut Table, key: &str, value: Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    let (last, head) = parts.split_last().ok_or("an empty key")?;
    let mut node: &mut Value = table
        .entry(head.first().copied().unwrap_or(last).to_string())
        .or_insert_with(|| Value::Table(Table::new()));
    if head.is_empty() {
        *node = value;
        return Ok(());
    }
    for (k, p) in parts.iter().enumerate().skip(1) {
        let so_far = parts[..k].join(".");
        let next = match node {
            Value::Table(t) => t
                .entry(p.to_string())
                .or_insert_with(|| Value::Table(Table::new())),
            Value::Array(a) => {
                let n = a.len();
                let i: usize = p.parse().map_err(|_| {
                    format!("{so_far} is a list: index it with a number, as {so_far}.0")
                })?;
                a.get_mut(i).ok_or_else(|| {
                    format!(
                        "{so_far} has {n} entries (indices 0 to {}), not {i}",
                        n.max(1) - 1
                    )
                })?
            }
            _ => {
                return Err(format!(
                    "{so_far} is a value, not a table: {key} cannot be set"
                ));
            }
        };
        node = next;
    }
    *node = value;
    Ok(())
}

/// The base scene: its table, its text and origin (errors in it are placed there), and
/// the limits its points are read under.
pub(super) struct Base<'a> {
    /// The base scene's table (without `[sweep]`).
    pub(super) table: Table,
    text: std::borrow::Cow<'a, str>,
    origin: String,
    limits: Limits,
}

impl<'a> Base<'a> {
    /// The base scene (the sweep file itself without `base`), and its resolved scene.
    pub(super) fn load(
        src: &Source<'a>,
        doc: &DeTable<'_>,
        base_path: Option<(String, Range<usize>)>,
        limits: Limits,
    ) -> Result<(Base<'a>, Scene), SceneError> {
        let (text, origin) = match base_path {
            None => (std::borrow::Cow::Borrowed(src.text), src.origin.to_string()),
            Some((file, span)) => {
                if let Some((k, _)) = in_file_order(doc)
                    .into_iter()
                    .find(|(k, _)| k.get_ref() != "sweep")
                {
                    return Err(src.err(
                        k.span(),
                        format!("a sweep with base = {file:?} holds only the [sweep] table; move [{}] into the base scene", k.get_ref()),
                    ));
                }
                let path = src.dir.join(&file);
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    src.err(
                        span.clone(),
                        format!("cannot read the base scene {}: {e}", path.display()),
                    )
                })?;
                not_a_sweep(src, &path, &text, span)?;
                (std::borrow::Cow::Owned(text), path.display().to_string())
            }
        };
        let mut table: Table = toml::from_str(&text).map_err(|e| SceneError {
            origin: origin.clone(),
            location: e.span().map(|s| line_col(&text, s.start)),
            message: e.message().trim_end().replace('\n', " "),
            too_large: None,
        })?;
        table.remove("sweep");
        let base = Base {
            table,
            text,
            origin,
            limits,
        };
        // The base on its own must be a scene: its errors are its own.
        let scene = base.scene_with(src, &[], &[])?;
        Ok((base, scene))
    }

    /// The scene of a point: the base with `params` set, resolved; an error is placed
    /// at the value of the sweep that caused it, or else in the base scene.
    pub(super) fn scene_with(
        &self,
        src: &Source<'_>,
        params: &[(String, Value)],
        spans: &[(String, Range<usize>)],
    ) -> Result<Scene, SceneError> {
        let mut table = self.table.clone();
        for (key, value) in params {
            set_path(&mut table, key, value.clone()).map_err(|m| SceneError {
                origin: src.origin.to_string(),
                location: None,
                message: m,
                too_large: None,
            })?;
        }
        let text = toml::to_string(&table).map_err(|e| SceneError {
            origin: src.origin.to_string(),
            location: None,
            message: format!("the point's scene cannot be written: {e}"),
            too_large: None,
        })?;
        Scene::parse_limited(&text, &self.origin, self.limits).map_err(|e| {
            let path = e.line().map(|l| path_at_line(&text, l)).unwrap_or_default();
            // The swept key the error is about: the same path, or the nearest one.
            let culprit = spans
                .iter()
                .filter(|(k, _)| {
                    !path.is_empty() && (k.starts_with(&path) || path.starts_with(k.as_str()))
                })
                .max_by_key(|(k, _)| common_prefix(k, &path))
                .or(spans.last());
            match culprit {
                Some((key, span)) => {
                    let what = if path.is_empty() || path == *key {
                        String::new()
                    } else {
                        format!(" (at {path})")
                    };
                    at(
                        src.origin,
                        src.text,
                        span.clone(),
                        format!(
                            "the scene refuses the point {}: {}{what}",
                            describe(params),
                            e.message
                        ),
                    )
                }
                None => SceneError {
                    location: span_of(&self.text, &path).map(|s| line_col(&self.text, s.start)),
                    ..e
                },
            }
        })
    }
}

/// Refuses a base that is itself a sweep (a `[sweep]` table), or this very file: a base
/// is a plain scene. Said at the `base` value, naming the base's `[sweep]` line.
fn not_a_sweep(
    src: &Source<'_>,
    path: &Path,
    text: &str,
    span: Range<usize>,
) -> Result<(), SceneError> {
    let same = |a: &Path, b: &Path| matches!((std::fs::canonicalize(a), std::fs::canonicalize(b)), (Ok(x), Ok(y)) if x == y);
    if same(path, Path::new(src.origin)) {
        return Err(src.err(
            span,
            "base names this sweep file itself (a circular base): base is the plain scene the sweep varies",
        ));
    }
    let Ok(doc) = DeTable::parse(text) else {
        return Ok(()); // its own errors are reported when it is read as a scene
    };
    let Some((key, value)) = doc.get_ref().iter().find(|(k, _)| k.get_ref() == "sweep") else {
        return Ok(());
    };
    let (line, _) = line_col(text, key.span().start);
    let theirs = match value.get_ref() {
        DeValue::Table(t) => t
            .iter()
            .find(|(k, _)| k.get_ref() == "base")
            .and_then(|(_, v)| {
                let DeValue::String(b) = v.get_ref() else {
                    return None;
                };
                let target = path.parent().unwrap_or(Path::new(".")).join(b.as_ref());
                Some(target)
            }),
        _ => None,
    };
    let circle = match theirs {
        Some(t) if same(&t, Path::new(src.origin)) => ", whose base is this file: a circular base",
        _ => "",
    };
    Err(src.err(
        span,
        format!(
            "the base scene {} is itself a sweep ([sweep] at its line {line}{circle}): a base is a plain scene without [sweep]; point base at the scene the sweeps vary",
            path.display()
        ),
    ))
}

fn common_prefix(a: &str, b: &str) -> usize {
    a.chars().zip(b.chars()).take_while(|(x, y)| x == y).count()
}

/// The dotted path of the key written at `line` of a scene text written by `toml`
/// (`[table]` and `[[array]]` headers, then `key = value` lines).
fn path_at_line(text: &str, line: usize) -> String {
    let mut table = String::new();
    let mut counts: Vec<(String, usize)> = Vec::new();
    for (k, l) in text.lines().enumerate() {
        let l = l.trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|r| r.strip_suffix("]]")) {
            let n = match counts.iter_mut().find(|c| c.0 == name) {
                Some(c) => {
                    c.1 += 1;
                    c.1
                }
                None => {
                    counts.push((name.to_string(), 0));
                    0
                }
            };
            table = format!("{name}.{n}");
        } else if let Some(name) = l.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            table = name.to_string();
        } else if k + 1 == line {
            let key = l.split('=').next().unwrap_or("").trim().trim_matches('"');
            return if table.is_empty() {
                key.to_string()
            } else {
                format!("{table}.{key}")
            };
        }
        if k + 1 == line {
            return table;
        }
    }
    table
}

/// The span of the key at a dotted path in a scene text (the nearest table when the
/// key is not written there).
fn span_of(text: &str, path: &str) -> Option<Range<usize>> {
    let doc = DeTable::parse(text).ok()?;
    let mut span = None;
    let mut node: Option<&DeValue<'_>> = None;
    for p in path.split('.') {
        let found = match node {
            None => doc
                .get_ref()
                .iter()
                .find(|(k, _)| k.get_ref() == p)
                .map(|(k, v)| (k.span(), v)),
            Some(DeValue::Table(t)) => t
                .iter()
                .find(|(k, _)| k.get_ref() == p)
                .map(|(k, v)| (k.span(), v)),
            Some(DeValue::Array(a)) => p
                .parse::<usize>()
                .ok()
                .and_then(|i| a.get(i))
                .map(|v| (v.span(), v)),
            _ => None,
        };
        let Some((s, v)) = found else { break };
        span = Some(s);
        node = Some(v.get_ref());
    }
    span
}
