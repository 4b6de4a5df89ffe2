//! The sweep file: read with the span of every key and value, expanded into points,
//! every point's scene resolved, and each error placed at its file and line.

use std::ops::Range;
use std::path::Path;

use toml::de::{DeTable, DeValue};
use toml::{Spanned, Table, Value};

use super::base::{Base, set_path};
use super::expand::Plan;
use super::{MAX_POINTS, SEED_KEY, Sweep, hints};
use crate::scene::{SceneError, line_col};
use crate::sizing::Limits;

/// An error at a byte span of a text named `origin`.
pub(super) fn at(
    origin: &str,
    text: &str,
    span: Range<usize>,
    message: impl Into<String>,
) -> SceneError {
    SceneError {
        origin: origin.to_string(),
        location: Some(line_col(text, span.start)),
        message: message.into(),
        too_large: None,
    }
}

/// One value of a parameter, with the span of its text in the sweep file.
#[derive(Clone)]
pub(super) struct Item {
    pub(super) value: Value,
    pub(super) span: Range<usize>,
}

/// A factor of the product: keys that vary together (one key, or a `zip` group).
pub(super) struct Factor {
    pub(super) keys: Vec<(String, Range<usize>)>,
    /// Per key, its values (all of the same length).
    pub(super) values: Vec<Vec<Item>>,
}

impl Factor {
    pub(super) fn len(&self) -> usize {
        self.values.first().map_or(1, Vec::len)
    }
}

/// The sweep file's text, where it came from, and its folder (for `base`).
pub(super) struct Source<'a> {
    pub(super) text: &'a str,
    pub(super) origin: &'a str,
    pub(super) dir: &'a Path,
}

impl Source<'_> {
    pub(super) fn err(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        at(self.origin, self.text, span, message)
    }

    /// The TOML value written at `span` (an element of a list), read on its own.
    fn value_at(&self, span: Range<usize>) -> Result<Value, SceneError> {
        let slice = &self.text[span.clone()];
        let table: Table = toml::from_str(&format!("v = {slice}"))
            .map_err(|e| self.err(span.clone(), format!("cannot read this value: {e}")))?;
        let v = table.get("v").cloned().unwrap_or(Value::Boolean(false));
        check_value(&v).map_err(|m| self.err(span, m))?;
        Ok(v)
    }
}

/// Refuses values a state point cannot hold exactly (dates, non-finite numbers).
fn check_value(v: &Value) -> Result<(), String> {
    match v {
        Value::Float(x) if !x.is_finite() => Err(format!("{x} is not a finite number")),
        Value::Datetime(_) => Err("a date is not a scene value".into()),
        Value::Array(a) => a.iter().try_for_each(check_value),
        Value::Table(t) => t.values().try_for_each(check_value),
        _ => Ok(()),
    }
}

/// Entries of a table in file order (the map itself is sorted by key).
pub(super) fn in_file_order<'a, 'i>(
    t: &'a DeTable<'i>,
) -> Vec<(
    &'a Spanned<std::borrow::Cow<'i, str>>,
    &'a Spanned<DeValue<'i>>,
)> {
    let mut v: Vec<_> = t.iter().collect();
    v.sort_by_key(|(k, _)| k.span().start);
    v
}

/// Reads and expands a sweep file (see the module documentation of [`super`]).
pub(super) fn parse(src: &Source<'_>, limits: Limits) -> Result<Sweep, SceneError> {
    let mut plan = plan(src, limits)?;
    let points = plan.resolve_all(src)?;
    Ok(Sweep {
        keys: plan.keys,
        replicas: plan.replicas.0,
        points,
        digest: plan.digest,
    })
}

/// Reads a sweep file and plans its points: every point's parameters and id, no scene
/// resolved but the base's.
pub(super) fn plan<'a>(src: &Source<'a>, limits: Limits) -> Result<Plan<'a>, SceneError> {
    let doc = DeTable::parse(src.text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        src.err(span, e.message().trim_end().replace('\n', " "))
    })?;
    let doc = doc.get_ref();
    let Some((sweep_key, sweep)) = doc.iter().find(|(k, _)| k.get_ref() == "sweep") else {
        if let Some(e) = hints::missing_sweep(src, doc) {
            return Err(e);
        }
        return Err(SceneError {
            origin: src.origin.to_string(),
            location: None,
            message: "no [sweep] table: a sweep file is a scene with a [sweep] table, or a [sweep] table with base = \"scene.toml\"".into(),
            too_large: None,
        });
    };
    let DeValue::Table(table) = sweep.get_ref() else {
        return Err(src.err(sweep_key.span(), "sweep must be a table"));
    };
    let mut base_path: Option<(String, Range<usize>)> = None;
    let mut replicas: Option<(usize, Range<usize>)> = None;
    let mut factors: Vec<Factor> = Vec::new();
    for (key, value) in in_file_order(table) {
        match key.get_ref().as_ref() {
            "base" => match value.get_ref() {
                DeValue::String(s) => base_path = Some((s.to_string(), value.span())),
                _ => return Err(src.err(value.span(), "base must be a file name (a string)")),
            },
            "replicas" => {
                let k = value
                    .get_ref()
                    .as_integer()
                    .and_then(|i| i64::from_str_radix(i.as_str(), i.radix()).ok())
                    .filter(|&k| k >= 1);
                match k {
                    Some(k) => replicas = Some((k as usize, value.span())),
                    None => {
                        return Err(src.err(value.span(), "replicas must be a whole number >= 1"));
                    }
                }
            }
            "zip" => {
                let DeValue::Array(groups) = value.get_ref() else {
                    return Err(src.err(
                        value.span(),
                        "zip must be a list of tables: [[sweep.zip]] groups of keys that vary together",
                    ));
                };
                for g in groups.iter() {
                    let DeValue::Table(t) = g.get_ref() else {
                        return Err(src.err(g.span(), "a zip group must be a table of keys"));
                    };
                    factors.push(zip_group(src, t, g.span())?);
                }
            }
            name => {
                if let Some(e) = hints::misspelled_setting(src, name, key.span(), value.get_ref()) {
                    return Err(e);
                }
                let values = values(src, name, key.span(), value)?;
                factors.push(Factor {
                    keys: vec![(name.to_string(), key.span())],
                    values: vec![values],
                });
            }
        }
    }
    if factors.is_empty() {
        return Err(src.err(
            sweep_key.span(),
            "the sweep varies nothing: give lists of values, as \"helix.dhat\" = [1.05, 1.5]",
        ));
    }
    factors.sort_by_key(|f| f.keys[0].1.start);
    let mut seen: Vec<&str> = Vec::new();
    for (key, span) in factors.iter().flat_map(|f| &f.keys) {
        if seen.contains(&key.as_str()) {
            return Err(src.err(span.clone(), format!("{key:?} is varied twice")));
        }
        seen.push(key);
    }
    let count = point_count(src, &factors, replicas.as_ref())?;
    let (base, base_scene) = Base::load(src, doc, base_path, limits)?;
    let (replicas, replicas_span) = replicas.unwrap_or((1, 0..0));
    if replicas > 1
        && let Some((_, span)) = factors
            .iter()
            .flat_map(|f| &f.keys)
            .find(|k| k.0 == SEED_KEY)
    {
        return Err(src.err(
                span.clone(),
                "brownian.seed is set by replicas (seed, seed + 1, ...): vary it or give replicas, not both",
            ));
    }
    let doc = base.document()?;
    for f in &factors {
        for (key, span) in &f.keys {
            set_path(&mut doc.get_ref().clone(), key, DeValue::Boolean(false))
                .map_err(|m| src.err(span.clone(), m))?;
        }
    }
    drop(doc);
    Plan::new(
        src,
        factors,
        (base, base_scene),
        count,
        (replicas, replicas_span),
    )
}

/// The number of points, refused past [`MAX_POINTS`] before anything is expanded (at
/// the key whose list crosses the limit).
fn point_count(
    src: &Source<'_>,
    factors: &[Factor],
    replicas: Option<&(usize, Range<usize>)>,
) -> Result<usize, SceneError> {
    let mut count: usize = 1;
    let sizes = factors
        .iter()
        .map(|f| (f.len(), f.keys[0].1.clone()))
        .chain(replicas.map(|(k, s)| (*k, s.clone())));
    for (n, span) in sizes {
        count = count.saturating_mul(n);
        if count > MAX_POINTS {
            return Err(src.err(
                span,
                format!(
                    "the sweep has {} points up to here, over the limit of {MAX_POINTS}: split it into several sweeps",
                    if count == usize::MAX {
                        "more than 2^64".to_string()
                    } else {
                        count.to_string()
                    }
                ),
            ));
        }
    }
    Ok(count)
}

/// A readable `key = value, ...` of a point.
pub(super) fn describe(params: &[(String, Value)]) -> String {
    let parts: Vec<String> = params.iter().map(|(k, v)| format!("{k} = {v}")).collect();
    format!("({})", parts.join(", "))
}

/// The values of a key: a non-empty list, or `{ linspace = [first, last, count] }`.
fn values(
    src: &Source<'_>,
    name: &str,
    key_span: Range<usize>,
    value: &Spanned<DeValue<'_>>,
) -> Result<Vec<Item>, SceneError> {
    if name.is_empty() || name.split('.').any(str::is_empty) {
        return Err(src.err(key_span, format!("{name:?} is not a dotted scene key")));
    }
    match value.get_ref() {
        DeValue::Array(items) if items.is_empty() => Err(src.err(
            value.span(),
            format!("{name:?} has an empty list: give at least one value"),
        )),
        DeValue::Array(items) => items
            .iter()
            .map(|i| {
                Ok(Item {
                    value: src.value_at(i.span())?,
                    span: i.span(),
                })
            })
            .collect(),
        DeValue::Table(t) if t.len() == 1 && t.iter().any(|(k, _)| k.get_ref() == "linspace") => {
            let v = src.value_at(value.span())?;
            let spec = v.get("linspace").and_then(Value::as_array);
            let nums: Option<(f64, f64, i64)> = spec.and_then(|a| match a.as_slice() {
                [a, b, Value::Integer(n)] => {
                    let f = |v: &Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
                    Some((f(a)?, f(b)?, *n))
                }
                _ => None,
            });
            match nums {
                Some((a, b, n)) if n >= 1 && n as usize <= MAX_POINTS => {
                    Ok(linspace(a, b, n as usize)
                        .into_iter()
                        .map(|x| Item {
                            value: Value::Float(x),
                            span: value.span(),
                        })
                        .collect())
                }
                _ => Err(src.err(
                    value.span(),
                    format!(
                        "{name:?}: linspace takes [first, last, count] with a whole count from 1 to {MAX_POINTS}"
                    ),
                )),
            }
        }
        DeValue::Table(_) => Err(src.err(
            key_span,
            format!(
                "{name:?} holds a table: write each scene key quoted and dotted, as \"{name}.key\" = [...], or give {{ linspace = [first, last, count] }}"
            ),
        )),
        _ => Err(src.err(
            value.span(),
            format!("{name:?} must be a list of values, as [1.0, 2.0]"),
        )),
    }
}

fn zip_group(src: &Source<'_>, t: &DeTable<'_>, span: Range<usize>) -> Result<Factor, SceneError> {
    let mut f = Factor {
        keys: Vec::new(),
        values: Vec::new(),
    };
    for (key, value) in in_file_order(t) {
        let vals = values(src, key.get_ref(), key.span(), value)?;
        if let Some(first) = f.values.first()
            && first.len() != vals.len()
        {
            return Err(src.err(
                    key.span(),
                    format!(
                        "a zip group's lists vary together and must have one length: {:?} has {}, {:?} has {}",
                        f.keys[0].0,
                        first.len(),
                        key.get_ref(),
                        vals.len()
                    ),
                ));
        }
        f.keys.push((key.get_ref().to_string(), key.span()));
        f.values.push(vals);
    }
    if f.keys.is_empty() {
        return Err(src.err(span, "an empty zip group"));
    }
    Ok(f)
}

/// `n` evenly spaced values from `a` to `b` (both included; `a` alone for `n = 1`):
/// `linspace` in sweep files, and the phase grid of the Figure 1 study.
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| a + (b - a) * k as f64 / (n - 1).max(1) as f64)
        .collect()
}
