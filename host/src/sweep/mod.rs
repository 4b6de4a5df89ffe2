//! Sweeps: a grid of scene parameters expanded into points, each run in its own folder
//! by whichever process, shard or cluster task gets it, and collected into one table.
//!
//! # The sweep file
//!
//! A scene file with a `[sweep]` table added, or a file holding only a `[sweep]` table
//! with `base = "scene.toml"` (relative to the sweep file):
//!
//! ```toml
//! [sweep]
//! base = "../scenes/figure1a.toml"
//! "integrator.dt" = [0.1, 0.05]                  # a list of values
//! "helix.head_ratio" = { linspace = [1.0, 2.5, 4] }   # first, last, count
//! replicas = 4                                   # Brownian runs: seeds s, s+1, s+2, s+3
//!
//! [[sweep.zip]]                                  # keys that vary together
//! "helix.dhat" = [1.50, 1.05]
//! "model.hydrodynamics" = ["rpy", "free-draining"]
//! ```
//!
//! * Keys are dotted scene keys, quoted; a number indexes a list of tables
//!   (`"particle.1.radius"`). A key may be one the base scene leaves to its default.
//! * The lists combine as a product, in file order, the last varying fastest; a
//!   `[[sweep.zip]]` group is one factor whose lists (of one length) vary together.
//! * `replicas = K` runs every point K times with `brownian.seed` = the base scene's
//!   seed (default 1) plus 0, 1, ..., K - 1; it needs thermal noise in every point.
//! * Every point is resolved and validated before anything runs, in time linear in the
//!   points. An unknown key, an empty list, a value the scene refuses, a
//!   point given twice (numbers compared as numbers), a base that is itself a sweep, a
//!   misspelled table or setting, or more than [`MAX_POINTS`] points is an error at its
//!   file, line and column (`sweep.toml:4:21: ...`), as for scenes. (One point run
//!   from the sweep file in a folder that already holds the sweep, whose points were
//!   all checked when it claimed the folder, is the only one resolved:
//!   [`Sweep::point_from_path`], [`run::run_point_of_file`].)
//!
//! # Points
//!
//! A point's *state point* is its parameters nested at their dots
//! (`{"helix": {"dhat": 1.05}, "integrator": {"dt": 0.1}}`, with `brownian.seed` for a
//! replica). Its id is the MD5 of the state point's canonical JSON, computed as signac
//! computes job ids ([`id`]), so `DIR` is a signac project (`.signac/config`,
//! `workspace -> points`) and a row project (`workflow.toml`) as it is.
//!
//! A folder holds one sweep ([`claim`]): `sweep.json` records the sweep's digest, which
//! covers every point's resolved scene, and another sweep is refused before anything
//! is written. The points' scenes are frozen in `DIR/frozen` ([`frozen`]) when the
//! sweep claims the folder; emitted jobs run them from there.
//!
//! `DIR/points/<id>/` holds `signac_statepoint.json`, `scene.toml` (the point's
//! resolved scene) and, once run, the files of a run (`summary.json`,
//! `observables.csv`, `trajectory.xyz`, `trajectory.gsd`, `checkpoint.json`). They are
//! byte-identical whichever process ran the point, except four fields of
//! `summary.json` that describe the execution: `wall_time_s`, `steps_per_second`,
//! `machine`, and `resumed_from` (the time a resumed run continued from).

mod base;
pub mod claim;
pub mod cluster;
pub mod emit;
mod expand;
mod file;
pub mod frozen;
mod hints;
pub mod id;
pub mod record;
mod report;
pub mod run;
mod state;

use std::path::Path;

use serde_json::Value as Json;
use toml::Value;

use crate::scene::{Scene, SceneError};
use crate::sizing::Limits;

pub use claim::AnotherSweep;
pub use emit::{Engine, SlurmOptions, emit};
pub use file::linspace;
pub use run::{RunReport, Selection, run_frozen, run_point_of_file, run_points, run_sweep};

/// Most points a sweep may have (replicas counted).
pub const MAX_POINTS: usize = 100_000;

/// The sweep's record in its folder.
pub const SWEEP_JSON: &str = "sweep.json";
/// The folder of the points in the sweep's folder.
pub const POINTS: &str = "points";
/// A point's parameters in its folder, as signac names it.
pub const STATEPOINT_JSON: &str = "signac_statepoint.json";
/// The key replicas set.
const SEED_KEY: &str = "brownian.seed";

/// One point of a sweep.
#[derive(Debug, Clone)]
pub struct Point {
    /// Position in the sweep (product order, replicas innermost).
    pub index: usize,
    /// The id: MD5 of the state point's canonical JSON ([`id::point_id`]).
    pub id: String,
    /// The parameters, as dotted keys in the sweep's key order.
    pub params: Vec<(String, Value)>,
    /// Which replica, when the sweep has `replicas` > 1.
    pub replica: Option<usize>,
    /// The parameters nested at their dots.
    pub statepoint: Json,
    /// The resolved scene.
    pub scene: Scene,
}

/// An expanded sweep file.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The parameter keys, in order (`brownian.seed` last with replicas).
    pub keys: Vec<String>,
    /// Runs per point (1 without replicas).
    pub replicas: usize,
    /// Every point.
    pub points: Vec<Point>,
    /// The sweep's digest ([`record::digest`]): which sweep a folder holds.
    pub digest: String,
}

/// One point of a sweep file, found and resolved alone ([`Sweep::point_from_path`]).
#[derive(Debug, Clone)]
pub struct Found {
    /// The point, its scene resolved.
    pub point: Point,
    /// The sweep's digest ([`record::digest`]).
    pub digest: String,
    /// The sweep's number of points.
    pub count: usize,
}

/// The text of a sweep file, and its name and folder.
fn read(path: &Path) -> Result<(String, String, &Path), SceneError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        origin: origin.clone(),
        location: None,
        message: format!("cannot read sweep file: {e}"),
        too_large: None,
    })?;
    Ok((text, origin, path.parent().unwrap_or(Path::new("."))))
}

/// `then` of a sweep file's plan (every point's id, no scene but the base's resolved).
fn planned<R>(
    path: &Path,
    then: impl FnOnce(&file::Source<'_>, expand::Plan<'_>) -> Result<R, SceneError>,
) -> Result<R, SceneError> {
    let (text, origin, dir) = read(path)?;
    let src = file::Source {
        text: &text,
        origin: &origin,
        dir,
    };
    let plan = file::plan(&src, Limits::default())?;
    then(&src, plan)
}

impl Sweep {
    /// Reads, expands and validates a sweep file.
    pub fn from_path(path: &Path) -> Result<Sweep, SceneError> {
        let (text, origin, dir) = read(path)?;
        Sweep::parse(&text, &origin, dir)
    }

    /// Expands and validates sweep text; `origin` names it in errors, `dir` is where
    /// `base` is found.
    pub fn parse(text: &str, origin: &str, dir: &Path) -> Result<Sweep, SceneError> {
        let src = file::Source { text, origin, dir };
        file::parse(&src, Limits::default())
    }

    /// Reads, expands and validates a sweep file as [`from_path`](Self::from_path)
    /// does, but lets each point's scene go once it is checked: the ids and state
    /// points (canonical JSON, [`id::canonical_json`]) of the points, in sweep order,
    /// in the memory of a few scenes (what `--dry-run` lists).
    pub fn check_path(path: &Path) -> Result<Vec<(String, String)>, SceneError> {
        planned(path, |src, plan| {
            plan.check_all(src)?;
            let drafts = plan.drafts.into_iter();
            Ok(drafts.map(|d| (d.id, d.canonical)).collect())
        })
    }

    /// The point of a sweep file with this id (or a unique prefix of it, at least 4
    /// characters), resolved alone: every point's parameters and id are computed (an
    /// MD5 each), no other scene is resolved; None when no point has the id. The
    /// sweep's digest says whether a folder already holds this sweep (whose points were
    /// all checked when it claimed the folder).
    pub fn point_from_path(path: &Path, id: &str) -> Result<Option<Found>, SceneError> {
        planned(path, |src, plan| {
            let Some(k) = plan.find(id) else {
                return Ok(None);
            };
            Ok(Some(Found {
                point: plan.resolve_one(src, k)?,
                count: plan.drafts.len(),
                digest: plan.digest,
            }))
        })
    }

    /// The point with this id (or a unique prefix of it, at least 4 characters).
    pub fn find(&self, id: &str) -> Option<&Point> {
        let exact = self.points.iter().find(|p| p.id == id);
        exact.or_else(|| {
            let mut m = self
                .points
                .iter()
                .filter(|p| id.len() >= 4 && p.id.starts_with(id));
            match (m.next(), m.next()) {
                (Some(p), None) => Some(p),
                _ => None,
            }
        })
    }
}

#[cfg(test)]
mod tests;
