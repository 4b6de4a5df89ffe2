//! `sweep.json`: a sweep's record in its folder. Every point, its id, parameters and
//! state point, the digest of its scene as run (`scene.toml`), and the sweep's own
//! digest, which says whose folder it is: a sweep file whose expansion has another
//! digest is another sweep, refused in this folder ([`super::claim`]).

use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value as Json;

use super::{SWEEP_JSON, Sweep};
use crate::output::fnv1a64;
use crate::scene::Scene;

/// The record's format: the library that writes it and the format's version.
pub const FORMAT: &str = "hydrorattle-host sweep 2";

/// The names earlier versions wrote for the formats still read: the same record under
/// the CLI's name ("host-demo sweep 2"), and format 1 (no digests), which a claim adopts
/// and a frozen run refuses with why.
pub const FORMERLY: [&str; 2] = ["host-demo sweep 2", "host-demo sweep 1"];

/// What `sweep.json` holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepRecord {
    /// Format name and version ([`FORMAT`]).
    pub format: String,
    /// How ids are computed.
    pub id: String,
    /// The sweep's digest ([`digest`]); absent in records of format 1.
    #[serde(default)]
    pub digest: Option<String>,
    /// Parameter keys, in order.
    pub keys: Vec<String>,
    /// Runs per point.
    pub replicas: usize,
    /// Number of points.
    pub count: usize,
    /// The points, in sweep order.
    pub points: Vec<PointRecord>,
}

/// One point in `sweep.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PointRecord {
    /// Position in the sweep.
    pub index: usize,
    /// Id (folder name).
    pub id: String,
    /// Replica number, with replicas.
    pub replica: Option<usize>,
    /// Parameters by dotted key.
    pub parameters: serde_json::Map<String, Json>,
    /// The state point.
    pub statepoint: Json,
    /// FNV-1a 64 of the point's `scene.toml` as its run writes it (absent in records
    /// of format 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_toml_fnv1a64: Option<String>,
}

/// The sweep's digest: FNV-1a 64 of its resolved base scene, keys, replica count and
/// point ids (`ids`) in order. With the ids (MD5s of the parameters) it covers every
/// point's whole resolved scene, and it costs one pass over the ids, not a scene per
/// point.
pub fn digest<'a>(
    base: &Scene,
    keys: &[String],
    replicas: usize,
    ids: impl IntoIterator<Item = &'a str>,
) -> String {
    let mut text = serde_json::to_vec(base).unwrap_or_default();
    text.extend_from_slice(format!("\n{keys:?}\n{replicas}\n").as_bytes());
    for id in ids {
        text.extend_from_slice(id.as_bytes());
        text.push(b'\n');
    }
    fnv1a64(&text)
}

impl Sweep {
    /// `sweep.json` of this sweep, with each point's `scene.toml` digest (in point
    /// order).
    pub fn record(&self, scene_digests: &[String]) -> SweepRecord {
        SweepRecord {
            format: FORMAT.into(),
            id: "md5 of json.dumps(statepoint, sort_keys=True), as signac.job.calc_id".into(),
            digest: Some(self.digest.clone()),
            keys: self.keys.clone(),
            replicas: self.replicas,
            count: self.points.len(),
            points: self
                .points
                .iter()
                .zip(scene_digests)
                .map(|(p, d)| PointRecord {
                    index: p.index,
                    id: p.id.clone(),
                    replica: p.replica,
                    parameters: p
                        .params
                        .iter()
                        .map(|(k, v)| (k.clone(), serde_json::to_value(v).unwrap_or(Json::Null)))
                        .collect(),
                    statepoint: p.statepoint.clone(),
                    scene_toml_fnv1a64: Some(d.clone()),
                })
                .collect(),
        }
    }
}

impl SweepRecord {
    /// The digest of the sweep recorded in `dir` (None when there is no record, or a
    /// record without one), read without the points (`sweep.json` of 10^5 points is
    /// 40 MB: its points parsed cost more than finding one point of the sweep file).
    pub fn read_digest(dir: &Path) -> Result<Option<String>> {
        #[derive(Deserialize)]
        struct Digest {
            #[serde(default)]
            digest: Option<String>,
        }
        let path = dir.join(SWEEP_JSON);
        let bytes = match std::fs::read(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            b => b.with_context(|| format!("reading {}", path.display()))?,
        };
        let d: Digest = serde_json::from_slice(&bytes)
            .with_context(|| format!("{}: not a sweep record", path.display()))?;
        Ok(d.digest)
    }

    /// The record in `dir`, or None when there is none.
    pub fn read(dir: &Path) -> Result<Option<SweepRecord>> {
        let path = dir.join(SWEEP_JSON);
        let text = match std::fs::read_to_string(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            t => t.with_context(|| format!("reading {}", path.display()))?,
        };
        let r = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a sweep record", path.display()))?;
        Ok(Some(r))
    }
}
