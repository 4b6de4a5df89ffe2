//! The base scene of a sweep and the scene of each point: the base's TOML table with
//! the point's values set at their dotted paths, resolved by the scene parser, and an
//! error placed at the sweep value that caused it (or else in the base scene).

use std::borrow::Cow;
use std::ops::Range;
use std::path::Path;

use serde::Deserialize;
use toml::de::{DeTable, DeValue};
use toml::{Spanned, Table, Value};

use super::file::{Source, at, describe, in_file_order};
use crate::scene::{Scene, SceneError, line_col};
use crate::sizing::Limits;

/// Sets the value at a dotted path of a parsed document (numbers index arrays, as
/// `particle.1.radius`); tables on the way are made when missing.
pub(super) fn set_path<'i>(
    table: &mut DeTable<'i>,
    key: &str,
    value: DeValue<'i>,
) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    let (last, head) = parts.split_last().ok_or("an empty key")?;
    let first = head.first().copied().unwrap_or(last);
    let mut node: &mut DeValue<'i> = child(table, first).get_mut();
    if head.is_empty() {
        *node = value;
        return Ok(());
    }
    for (k, p) in parts.iter().enumerate().skip(1) {
        let so_far = || parts[..k].join(".");
        let next = match node {
            DeValue::Table(t) => child(t, p),
            DeValue::Array(a) => {
                let n = a.len();
                let i: usize = p.parse().map_err(|_| {
                    let so_far = so_far();
                    format!("{so_far} is a list: index it with a number, as {so_far}.0")
                })?;
                a.get_mut(i).ok_or_else(|| {
                    format!(
                        "{} has {n} entries (indices 0 to {}), not {i}",
                        so_far(),
                        n.max(1) - 1
                    )
                })?
            }
            _ => {
                return Err(format!(
                    "{} is a value, not a table: {key} cannot be set",
                    so_far()
                ));
            }
        };
        node = next.get_mut();
    }
    *node = value;
    Ok(())
}

/// The entry `key` of a table, an empty table put there when missing (looked up
/// first: a point sets keys the base mostly has, and a key is allocated only to add it).
fn child<'a, 'i>(t: &'a mut DeTable<'i>, key: &str) -> &'a mut Spanned<DeValue<'i>> {
    if !t.contains_key(key) {
        let table = Spanned::new(0..0, DeValue::Table(DeTable::new()));
        t.insert(Spanned::new(0..0, Cow::Owned(key.to_string())), table);
    }
    t.get_mut(key).expect("the entry was just put there")
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
        let scene = base.scene_with(src, &base.document()?, &[], &[], Vec::new)?;
        Ok((base, scene))
    }

    /// The base scene parsed, without `[sweep]` (its spans are in the base's text):
    /// parsed once, a copy per point.
    pub(super) fn document(&self) -> Result<Spanned<DeTable<'_>>, SceneError> {
        let mut doc = DeTable::parse(&self.text).map_err(|e| SceneError {
            origin: self.origin.clone(),
            location: e.span().map(|s| line_col(&self.text, s.start)),
            message: e.message().trim_end().replace('\n', " "),
            too_large: None,
        })?;
        doc.get_mut().remove("sweep");
        Ok(doc)
    }

    /// The scene of a point: the base document `doc` with `params` set (`values`: each
    /// parameter's value parsed), resolved; an error is placed at the value of the sweep
    /// that caused it (`spans`: each value's place in the sweep file), or else in the
    /// base scene.
    pub(super) fn scene_with<'d>(
        &self,
        src: &Source<'_>,
        doc: &Spanned<DeTable<'d>>,
        params: &[(String, Value)],
        values: &[&DeValue<'d>],
        spans: impl FnOnce() -> Vec<(String, Range<usize>)>,
    ) -> Result<Scene, SceneError> {
        let point = || {
            let mut point = doc.clone();
            for ((key, _), value) in params.iter().zip(values) {
                set_path(point.get_mut(), key, (*value).clone()).map_err(|m| SceneError {
                    origin: src.origin.to_string(),
                    location: None,
                    message: m,
                    too_large: None,
                })?;
            }
            Ok::<_, SceneError>(point)
        };
        if let Some((mut scene, method_at)) = Scene::from_document(point()?, self.limits) {
            // The line of the box's method in the base, unless the point sets it.
            let swept = params
                .iter()
                .any(|(k, _)| k == "box" || k.starts_with("box."));
            if let Some(b) = scene.periodic.as_mut() {
                b.method_line = method_at
                    .filter(|_| !swept)
                    .map(|at| line_col(&self.text, at).0);
            }
            return Ok(scene);
        }
        // Refused: the point's scene written as text and parsed, to place the error.
        let unwritable = |e: String| SceneError {
            origin: src.origin.to_string(),
            location: None,
            message: format!("the point's scene cannot be written: {e}"),
            too_large: None,
        };
        let table = Table::deserialize(toml::de::Deserializer::from(point()?))
            .map_err(|e| unwritable(e.to_string()))?;
        let text = toml::to_string(&table).map_err(|e| unwritable(e.to_string()))?;
        Scene::parse_limited(&text, &self.origin, self.limits).map_err(|e| {
            let spans = spans();
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
