//! The frozen copy of a sweep: each point's resolved scene in `DIR/frozen/ID.toml`,
//! written when the sweep first claims its folder (an emitted job's tasks find it
//! there), with the digest of its scene as run in `sweep.json`.
//!
//! The emitted SLURM, GNU parallel and row tasks run `host-demo sweep --frozen --out
//! DIR`: they read neither the sweep file nor its base scenes, so editing them after
//! the job was emitted changes nothing the job runs. A task reads only `sweep.json` and
//! its own points' frozen scenes (no expansion), and refuses a point whose frozen scene
//! no longer gives the scene recorded for it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use rayon::prelude::*;

use super::record::SweepRecord;
use super::run::{Selection, as_run};
use super::{Point, Sweep};
use crate::output::{fnv1a64, write_atomic};
use crate::scene::Scene;
use crate::sizing::Limits;

/// The folder of the frozen scenes in a sweep's folder.
pub const FROZEN: &str = "frozen";

/// The frozen scene of point `id` in the sweep folder `dir`.
pub fn frozen_path(dir: &Path, id: &str) -> PathBuf {
    dir.join(FROZEN).join(format!("{id}.toml"))
}

/// The text of a point's scene as its run writes `scene.toml`, and its digest.
pub fn run_text(point: &Point) -> (String, String) {
    let text = as_run(&point.scene, &point.id).to_toml();
    let digest = fnv1a64(text.as_bytes());
    (text, digest)
}

/// Writes every point's scene to `DIR/frozen/ID.toml` (on every core); returns the
/// digest of each point's `scene.toml`, in point order.
pub(super) fn freeze(sweep: &Sweep, dir: &Path) -> Result<Vec<String>> {
    let folder = dir.join(FROZEN);
    std::fs::create_dir_all(&folder).with_context(|| format!("creating {}", folder.display()))?;
    sweep
        .points
        .par_iter()
        .map(|p| {
            write_atomic(&frozen_path(dir, &p.id), p.scene.to_toml().as_bytes())?;
            Ok(run_text(p).1)
        })
        .collect()
}

/// A point of a frozen sweep that cannot run, and why.
pub type Refused = (String, String);

/// The selected points of the sweep frozen in `dir`: each read from its frozen scene
/// and checked against `sweep.json`; a point whose frozen scene is missing, unreadable,
/// or no longer gives the recorded scene is refused (with why), and the rest run.
pub fn load(dir: &Path, selection: &Selection) -> Result<(SweepRecord, Vec<Point>, Vec<Refused>)> {
    let Some(record) = SweepRecord::read(dir)? else {
        bail!(
            "{}: no sweep.json: nothing was emitted or run into this folder (emit or run a sweep file into it first)",
            dir.display()
        );
    };
    let chosen: Vec<&super::record::PointRecord> = match selection {
        Selection::All => record.points.iter().collect(),
        Selection::Shard { k, n } => record.points.iter().filter(|p| p.index % n == *k).collect(),
        Selection::Point(id) => {
            let exact = record.points.iter().find(|p| p.id == *id);
            let mut prefix = record
                .points
                .iter()
                .filter(|p| id.len() >= 4 && p.id.starts_with(id.as_str()));
            match exact.or_else(|| match (prefix.next(), prefix.next()) {
                (Some(p), None) => Some(p),
                _ => None,
            }) {
                Some(p) => vec![p],
                None => bail!(
                    "the sweep in {} has no point {id:?} (see sweep.json)",
                    dir.display()
                ),
            }
        }
    };
    let loaded: Vec<Result<Point, Refused>> = chosen
        .par_iter()
        .map(|r| thaw(dir, &record, r).map_err(|e| (r.id.clone(), format!("{e:#}"))))
        .collect();
    let (mut points, mut refused) = (Vec::new(), Vec::new());
    for l in loaded {
        match l {
            Ok(p) => points.push(p),
            Err(r) => refused.push(r),
        }
    }
    Ok((record, points, refused))
}

/// One point of a frozen sweep, its scene read and checked.
fn thaw(dir: &Path, record: &SweepRecord, r: &super::record::PointRecord) -> Result<Point> {
    let Some(want) = &r.scene_toml_fnv1a64 else {
        bail!(
            "sweep.json records no scene digest (format 1, from an older hydrorattle-host): run the sweep file into a new folder"
        );
    };
    let path = frozen_path(dir, &r.id);
    let scene = Scene::from_path_limited(&path, Limits::default())?;
    let params = record
        .keys
        .iter()
        .map(|k| {
            let v = r.parameters.get(k).cloned().unwrap_or_default();
            let v: toml::Value = serde_json::from_value(v)
                .with_context(|| format!("sweep.json: point {}: parameter {k}", r.id))?;
            Ok((k.clone(), v))
        })
        .collect::<Result<_>>()?;
    let point = Point {
        index: r.index,
        id: r.id.clone(),
        params,
        replica: r.replica,
        statepoint: r.statepoint.clone(),
        scene,
    };
    let found = run_text(&point).1;
    if found != *want {
        bail!(
            "{}: this frozen scene gives a scene.toml of digest {found} where sweep.json records {want}: it was changed after the sweep was emitted; the point is not run",
            path.display()
        );
    }
    Ok(point)
}
