//! The points of a sweep: the product of its factors (the last varying fastest), with
//! replicas innermost, each point's id, a duplicate refused, and every scene resolved.
//!
//! In two passes. The plan ([`Plan::new`]) gives every point its parameters, state
//! point and id, and refuses a duplicate, without a scene: what finding one point by
//! its id needs ([`Plan::find`]). Then the scenes are resolved, all of them
//! ([`Plan::resolve_all`]) or one ([`Plan::resolve_one`]).
//!
//! Linear in the number of points: duplicates are found by a hash of each point's
//! parameters with numbers compared as numbers (`2` and `2.0` are one value). The base
//! scene and every value of the sweep are parsed once; a point's scene is a copy of
//! the base's parsed document with the point's values set in it, resolved without
//! writing or reading text ([`Base::scene_with`]). The scenes, each independent of the
//! others, are resolved on every core (the result, and the error reported, do not
//! depend on the core count: the first failing point in sweep order is the one named).

use std::collections::HashMap;
use std::ops::Range;

use rayon::prelude::*;
use serde_json::Value as Json;
use toml::Value;
use toml::de::{DeTable, DeValue};

use super::base::Base;
use super::file::{Factor, Source, describe};
use super::id::{canonical_json, md5_hex, push_python_float};
use super::{Point, SEED_KEY, record};
use crate::scene::{DEFAULT_SEED, Scene, SceneError};

/// A point before its scene is resolved (its parameters follow from its position:
/// [`Plan::params`]).
pub(super) struct Draft {
    /// The id: MD5 of the state point's canonical JSON.
    pub(super) id: String,
    /// The state point's canonical JSON ([`canonical_json`]).
    pub(super) canonical: String,
}

/// A sweep expanded into its points' parameters and ids, scenes not yet resolved.
pub(super) struct Plan<'a> {
    factors: Vec<Factor>,
    base: Base<'a>,
    /// The base scene, resolved.
    pub(super) base_scene: Scene,
    /// Runs per point, and the span of `replicas` in the sweep file.
    pub(super) replicas: (usize, Range<usize>),
    seed0: i64,
    /// The parameter keys, in order (`brownian.seed` last with replicas).
    pub(super) keys: Vec<String>,
    /// Every point, in sweep order.
    pub(super) drafts: Vec<Draft>,
    /// The sweep's digest ([`record::digest`]).
    pub(super) digest: String,
}

/// The text of each value of the sweep (per factor, per key, per value) and of each
/// replica's seed, as TOML writes them: parsed once into the values set in the points'
/// documents.
struct Texts {
    values: Vec<Vec<Vec<String>>>,
    seeds: Vec<String>,
}

/// What every point's scene is made from: the base document and each value, parsed.
struct Parts<'t> {
    doc: toml::Spanned<DeTable<'t>>,
    values: Vec<Vec<Vec<DeValue<'t>>>>,
    seeds: Vec<DeValue<'t>>,
}

impl<'a> Plan<'a> {
    /// Expands `factors` over `base` into `count` points (`replicas` runs of each
    /// combination), each with its id; errors at the sweep value that causes them.
    pub(super) fn new(
        src: &Source<'_>,
        factors: Vec<Factor>,
        (base, base_scene): (Base<'a>, Scene),
        count: usize,
        replicas: (usize, Range<usize>),
    ) -> Result<Plan<'a>, SceneError> {
        let seed0 = base
            .table
            .get("brownian")
            .and_then(|b| b.get("seed"))
            .and_then(Value::as_integer)
            .unwrap_or(DEFAULT_SEED as i64);
        let mut plan = Plan {
            factors,
            base,
            base_scene,
            replicas,
            seed0,
            keys: Vec::new(),
            drafts: Vec::new(),
            digest: String::new(),
        };
        plan.refuse_duplicates(src)?;
        plan.drafts = (0..count).into_par_iter().map(|k| plan.draft(k)).collect();
        plan.keys = plan.params(0).into_iter().map(|(k, _)| k).collect();
        let ids = plan.drafts.iter().map(|d| d.id.as_str());
        plan.digest = record::digest(&plan.base_scene, &plan.keys, plan.replicas.0, ids);
        Ok(plan)
    }

    /// Which value of each factor point `index` takes (the last factor varying fastest,
    /// replicas innermost), and its replica.
    fn pick(&self, index: usize) -> (Vec<usize>, Option<usize>) {
        let replicas = self.replicas.0;
        let mut rest = index / replicas;
        let mut pick = vec![0; self.factors.len()];
        for (p, f) in pick.iter_mut().zip(&self.factors).rev() {
            *p = rest % f.len();
            rest /= f.len();
        }
        (pick, (replicas > 1).then_some(index % replicas))
    }

    /// The parameters of point `index`, as dotted keys in the sweep's key order.
    fn params(&self, index: usize) -> Vec<(String, Value)> {
        let (pick, replica) = self.pick(index);
        let mut params: Vec<(String, Value)> = Vec::new();
        for (f, &k) in self.factors.iter().zip(&pick) {
            for ((key, _), vals) in f.keys.iter().zip(&f.values) {
                params.push((key.clone(), vals[k].value.clone()));
            }
        }
        if let Some(r) = replica {
            params.push((SEED_KEY.to_string(), Value::Integer(self.seed0 + r as i64)));
        }
        params
    }

    /// Point `index` before its scene: its id.
    fn draft(&self, index: usize) -> Draft {
        let canonical = canonical_json(&statepoint(&self.params(index)));
        Draft {
            id: md5_hex(canonical.as_bytes()),
            canonical,
        }
    }

    /// Point `index` with `scene`.
    fn point(&self, index: usize, id: String, scene: Scene) -> Point {
        let params = self.params(index);
        Point {
            index,
            id,
            statepoint: statepoint(&params),
            replica: self.pick(index).1,
            params,
            scene,
        }
    }

    /// The span in the sweep file of each value of point `index`.
    fn spans(&self, index: usize) -> Vec<(String, Range<usize>)> {
        let mut spans = Vec::new();
        for (f, &k) in self.factors.iter().zip(&self.pick(index).0) {
            for ((key, _), vals) in f.keys.iter().zip(&f.values) {
                spans.push((key.clone(), vals[k].span.clone()));
            }
        }
        spans
    }

    /// The point with this id, or the only one whose id starts with it (4 characters
    /// at least): its position.
    pub(super) fn find(&self, id: &str) -> Option<usize> {
        let exact = self.drafts.iter().position(|d| d.id == id);
        exact.or_else(|| {
            let mut m = (0..self.drafts.len())
                .filter(|&k| id.len() >= 4 && self.drafts[k].id.starts_with(id));
            match (m.next(), m.next()) {
                (Some(k), None) => Some(k),
                _ => None,
            }
        })
    }

    /// Every point with its scene resolved, in sweep order; the first point in sweep
    /// order that the scene refuses is the error.
    pub(super) fn resolve_all(&mut self, src: &Source<'_>) -> Result<Vec<Point>, SceneError> {
        let drafts = std::mem::take(&mut self.drafts);
        let texts = self.texts();
        let parts = self.parts(src, &texts)?;
        let resolved: Vec<Result<Point, SceneError>> = drafts
            .into_par_iter()
            .enumerate()
            .map(|(index, d)| Ok(self.point(index, d.id, self.scene_of(src, &parts, index)?)))
            .collect();
        resolved.into_iter().collect()
    }

    /// Resolves every point's scene and lets it go (what a check needs: the points'
    /// scenes are not held, so the memory stays that of a few scenes); the first point
    /// in sweep order that the scene refuses is the error.
    pub(super) fn check_all(&self, src: &Source<'_>) -> Result<(), SceneError> {
        let texts = self.texts();
        let parts = self.parts(src, &texts)?;
        let checked: Vec<Option<SceneError>> = (0..self.drafts.len())
            .into_par_iter()
            .map(|index| self.scene_of(src, &parts, index).err())
            .collect();
        checked.into_iter().flatten().next().map_or(Ok(()), Err)
    }

    /// Point `index` alone, its scene resolved.
    pub(super) fn resolve_one(&self, src: &Source<'_>, index: usize) -> Result<Point, SceneError> {
        let texts = self.texts();
        let parts = self.parts(src, &texts)?;
        let scene = self.scene_of(src, &parts, index)?;
        Ok(self.point(index, self.drafts[index].id.clone(), scene))
    }

    fn texts(&self) -> Texts {
        let values = self.factors.iter().map(|f| {
            let per_key = f.values.iter().map(|vals| {
                // A value's inline TOML text (a float as the shortest digits that read
                // back to it, as the scene text a point was once written as held).
                vals.iter().map(|item| item.value.to_string()).collect()
            });
            per_key.collect()
        });
        let seeds = (0..self.replicas.0 as i64).map(|r| (self.seed0 + r).to_string());
        Texts {
            values: values.collect(),
            seeds: seeds.collect(),
        }
    }

    fn parts<'t>(&'t self, src: &Source<'_>, texts: &'t Texts) -> Result<Parts<'t>, SceneError> {
        let parse = |text: &'t String, span: Range<usize>| {
            DeValue::parse(text)
                .map(toml::Spanned::into_inner)
                .map_err(|e| src.err(span, format!("cannot read this value: {e}")))
        };
        let mut values = Vec::with_capacity(self.factors.len());
        for (f, per_key) in self.factors.iter().zip(&texts.values) {
            let mut keys = Vec::with_capacity(per_key.len());
            for (vals, texts) in f.values.iter().zip(per_key) {
                let parsed = vals
                    .iter()
                    .zip(texts)
                    .map(|(v, t)| parse(t, v.span.clone()));
                keys.push(parsed.collect::<Result<Vec<_>, _>>()?);
            }
            values.push(keys);
        }
        let seeds = texts
            .seeds
            .iter()
            .map(|t| parse(t, self.replicas.1.clone()));
        Ok(Parts {
            doc: self.base.document()?,
            values,
            seeds: seeds.collect::<Result<_, _>>()?,
        })
    }

    /// The scene of point `index`, resolved from `parts`.
    fn scene_of(
        &self,
        src: &Source<'_>,
        parts: &Parts<'_>,
        index: usize,
    ) -> Result<Scene, SceneError> {
        let (pick, replica) = self.pick(index);
        let params = self.params(index);
        let mut values: Vec<&DeValue<'_>> = Vec::with_capacity(params.len());
        for (&k, per_key) in pick.iter().zip(&parts.values) {
            values.extend(per_key.iter().map(|vals| &vals[k]));
        }
        values.extend(replica.map(|r| &parts.seeds[r]));
        let spans = || self.spans(index);
        let scene = self
            .base
            .scene_with(src, &parts.doc, &params, &values, spans)?;
        let (replicas, span) = &self.replicas;
        if *replicas > 1 && !scene.brownian.is_some_and(|b| b.temperature > 0.0) {
            return Err(src.err(
                span.clone(),
                format!(
                    "replicas = {replicas} would repeat a deterministic run: the point {} has no thermal noise ([brownian] temperature > 0)",
                    describe(&params)
                ),
            ));
        }
        Ok(scene)
    }

    /// Refuses a point given twice (numbers compared as numbers), at the first value of
    /// the later one, naming the earlier.
    ///
    /// A point repeats an earlier one exactly when, in some factor, its row of values
    /// repeats an earlier row (the other factors' rows alike): the product makes every
    /// combination once. So the first repeat in sweep order is the first repeated row
    /// of some factor with every other factor at its first row, found in the factors'
    /// rows alone, not the points.
    fn refuse_duplicates(&self, src: &Source<'_>) -> Result<(), SceneError> {
        // (later, earlier) point index of the first repeat, over the factors.
        let mut first: Option<(usize, usize)> = None;
        let mut stride = self.replicas.0;
        for f in self.factors.iter().rev() {
            let mut seen: HashMap<String, usize> = HashMap::with_capacity(f.len());
            for row in 0..f.len() {
                let key = numeric_key(f.values.iter().map(|vals| &vals[row].value));
                if let Some(earlier) = seen.insert(key, row) {
                    let found = (row * stride, earlier * stride);
                    if first.is_none_or(|(p, _)| found.0 < p) {
                        first = Some(found);
                    }
                    break;
                }
            }
            stride *= f.len();
        }
        let Some((later, earlier)) = first else {
            return Ok(());
        };
        let (ours, theirs) = (self.params(later), self.params(earlier));
        // The value that makes the later point equal the earlier one: the first whose
        // text differs (2.0 against 2), else the first value.
        let spans = (self.spans(later), self.spans(earlier));
        let differs = spans
            .0
            .iter()
            .zip(&spans.1)
            .find(|(a, b)| a.1 != b.1)
            .map(|(a, _)| a.1.clone());
        let span = differs.or_else(|| spans.0.first().map(|s| s.1.clone()));
        Err(src.err(
            span.unwrap_or(0..0),
            format!(
                "the point {} is given twice (it is point {earlier} already{})",
                describe(&ours),
                if ours == theirs {
                    String::new()
                } else {
                    format!(
                        ", as {}: values equal as numbers are one value",
                        describe(&theirs)
                    )
                }
            ),
        ))
    }
}

/// Values as text in which numbers equal as numbers are equal (integers written as
/// floats): two rows of a factor with one text are one.
fn numeric_key<'v>(values: impl Iterator<Item = &'v Value>) -> String {
    fn put(out: &mut String, v: &Value) {
        match v {
            Value::Integer(i) => push_python_float(out, *i as f64),
            // `+ 0.0` turns -0.0 into 0.0: equal as numbers, and no parameter tells
            // them apart.
            Value::Float(x) => push_python_float(out, *x + 0.0),
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
    for v in values {
        put(&mut out, v);
        out.push('\u{1f}');
    }
    out
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
