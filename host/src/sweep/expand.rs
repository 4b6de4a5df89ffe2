//! The points of a sweep: the product of its factors (the last varying fastest), with
//! replicas innermost, each point's id, a duplicate refused, and every scene resolved.
//!
//! Linear in the number of points: duplicates are found by a hash of each point's
//! parameters with numbers compared as numbers (`2` and `2.0` are one value), and the
//! scenes, each independent of the others, are resolved on every core (the result,
//! and the error reported, do not depend on the core count: the first failing point
//! in sweep order is the one named).

use std::collections::HashMap;
use std::ops::Range;

use rayon::prelude::*;
use serde_json::Value as Json;
use toml::Value;

use super::base::Base;
use super::file::{Factor, Source, describe};
use super::id::{point_id, python_float};
use super::{Point, SEED_KEY};
use crate::scene::{DEFAULT_SEED, SceneError};

/// The parameters of one point before its scene is resolved: values, and the span of
/// each value in the sweep file.
struct Draft {
    params: Vec<(String, Value)>,
    spans: Vec<(String, Range<usize>)>,
    replica: Option<usize>,
}

/// Expands `factors` over `base` into `count` points (`replicas` runs of each
/// combination); errors at the sweep value that causes them.
pub(super) fn points(
    src: &Source<'_>,
    factors: &[Factor],
    base: &Base<'_>,
    count: usize,
    (replicas, replicas_span): (usize, Range<usize>),
) -> Result<Vec<Point>, SceneError> {
    let seed0 = base
        .table
        .get("brownian")
        .and_then(|b| b.get("seed"))
        .and_then(Value::as_integer)
        .unwrap_or(DEFAULT_SEED as i64);
    let mut drafts: Vec<Draft> = Vec::with_capacity(count);
    let mut index = vec![0usize; factors.len()];
    for _ in 0..count / replicas {
        let mut params: Vec<(String, Value)> = Vec::new();
        let mut spans: Vec<(String, Range<usize>)> = Vec::new();
        for (f, &k) in factors.iter().zip(&index) {
            for ((key, _), vals) in f.keys.iter().zip(&f.values) {
                params.push((key.clone(), vals[k].value.clone()));
                spans.push((key.clone(), vals[k].span.clone()));
            }
        }
        for r in 0..replicas {
            let mut params = params.clone();
            if replicas > 1 {
                params.push((SEED_KEY.to_string(), Value::Integer(seed0 + r as i64)));
            }
            drafts.push(Draft {
                params,
                spans: spans.clone(),
                replica: (replicas > 1).then_some(r),
            });
        }
        // The next combination: the last factor varies fastest.
        for (k, f) in index.iter_mut().zip(factors).rev() {
            *k += 1;
            if *k < f.len() {
                break;
            }
            *k = 0;
        }
    }
    refuse_duplicates(src, &drafts)?;
    let resolved: Vec<Result<Point, SceneError>> = drafts
        .into_par_iter()
        .enumerate()
        .map(|(index, d)| {
            let scene = base.scene_with(src, &d.params, &d.spans)?;
            if replicas > 1 && !scene.brownian.is_some_and(|b| b.temperature > 0.0) {
                return Err(src.err(
                    replicas_span.clone(),
                    format!(
                        "replicas = {replicas} would repeat a deterministic run: the point {} has no thermal noise ([brownian] temperature > 0)",
                        describe(&d.params)
                    ),
                ));
            }
            let statepoint = statepoint(&d.params);
            Ok(Point {
                index,
                id: point_id(&statepoint),
                params: d.params,
                replica: d.replica,
                statepoint,
                scene,
            })
        })
        .collect();
    resolved.into_iter().collect()
}

/// A point's parameters as text in which numbers equal as numbers are equal (integers
/// written as floats): two points with one text are one scene.
fn numeric_key(params: &[(String, Value)]) -> String {
    fn put(out: &mut String, v: &Value) {
        match v {
            Value::Integer(i) => out.push_str(&python_float(*i as f64)),
            Value::Float(x) => out.push_str(&python_float(*x)),
            Value::Array(a) => {
                out.push('[');
                for x in a {
                    put(out, x);
                    out.push(',');
                }
                out.push(']');
            }
            Value::Table(t) => {
                out.push('{');
                for (k, x) in t {
                    out.push_str(&format!("{k:?}="));
                    put(out, x);
                    out.push(',');
                }
                out.push('}');
            }
            other => out.push_str(&other.to_string()),
        }
    }
    let mut out = String::new();
    for (_, v) in params {
        put(&mut out, v);
        out.push('\u{1f}');
    }
    out
}

/// Refuses a point given twice (numbers compared as numbers), at the first value of
/// the later one, naming the earlier.
fn refuse_duplicates(src: &Source<'_>, drafts: &[Draft]) -> Result<(), SceneError> {
    let mut seen: HashMap<String, usize> = HashMap::with_capacity(drafts.len());
    for (k, d) in drafts.iter().enumerate() {
        if let Some(first) = seen.insert(numeric_key(&d.params), k) {
            // The value that makes the later point equal the earlier one: the first
            // whose text differs (2.0 against 2), else the first value.
            let differs = d
                .spans
                .iter()
                .zip(&drafts[first].spans)
                .find(|(a, b)| a.1 != b.1)
                .map(|(a, _)| a.1.clone());
            let span = differs.or_else(|| d.spans.first().map(|s| s.1.clone()));
            return Err(src.err(
                span.unwrap_or(0..0),
                format!(
                    "the point {} is given twice (it is point {first} already{})",
                    describe(&d.params),
                    if d.params == drafts[first].params {
                        String::new()
                    } else {
                        format!(
                            ", as {}: values equal as numbers are one value",
                            describe(&drafts[first].params)
                        )
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// The state point of a point: its parameters nested at their dots, as signac nests
/// dotted keys (`{"helix": {"dhat": 1.05}}`).
pub(super) fn statepoint(params: &[(String, Value)]) -> Json {
    let mut root = serde_json::Map::new();
    for (key, value) in params {
        let parts: Vec<&str> = key.split('.').collect();
        let mut node = &mut root;
        for p in &parts[..parts.len() - 1] {
            let entry = node
                .entry(p.to_string())
                .or_insert_with(|| Json::Object(serde_json::Map::new()));
            if !entry.is_object() {
                *entry = Json::Object(serde_json::Map::new());
            }
            node = entry.as_object_mut().expect("an object was just put here");
        }
        let json = serde_json::to_value(value).unwrap_or(Json::Null);
        node.insert(parts[parts.len() - 1].to_string(), json);
    }
    Json::Object(root)
}
