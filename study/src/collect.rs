//! `host-demo collect DIR`: every point of a sweep in one table, `collected.csv`, and
//! charts of an observable against a parameter with replica means and error bars.
//!
//! Columns: `id`, `index`, the parameters (dotted keys, `brownian.seed` with
//! replicas), `replica`, `status`, `steps`, `steps_done`, `outcome`, the final
//! observables (`observables.csv`'s last row), `twist_rate`, `front_correlation`,
//! `mean_iterations`, one column per claim of the paper (`claim_<id>`: holds, transient
//! or fails, where the point is a Figure 1 case, empty otherwise), `failure`, and last
//! the two columns that depend on the machine and its load, `wall_time_s` and
//! `steps_per_second`.
//!
//! Status: `done`; `stopped_early` (a step failed: the summary says why); `error` (the
//! run could not start: `error.txt`); `corrupt` (a summary, but the data files are not
//! those it records: cut short or overwritten since, by size or digest); `foreign` (the
//! folder's `scene.toml` is not the one `sweep.json` records for the point: another
//! sweep's, or a run resumed by hand); `running` (not done, and a live process holds
//! the point's lock: a job is running it now); `unfinished` (a checkpoint, no summary);
//! `missing`. `unfinished`, `missing`, `error` and `corrupt` points run again when the
//! sweep does ([`Problem::reruns`]); a `running` point is left to the process running it.
//!
//! A point is a Figure 1 case when its helix is one of the paper's three. Its claims
//! are judged on its own observables; a claim comparing two cases ("settles faster
//! than (a)") also needs the other case's point with the same parameters apart from
//! the helix, and is left empty without one.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde_json::Value as Json;

use crate::claims::{CaseRun, SPECS, claims};
use hydrorattle_host::output::{
    AtomicFile, CsvWriter, FileCheck, FolderLock, fnv1a64, format_f64, mismatch,
};
use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::{
    CHECKPOINT, COLUMNS, Front, OBSERVABLES_CSV, Observables, SCENE_TOML, SUMMARY_JSON,
};
use hydrorattle_host::sweep::SWEEP_JSON;
use hydrorattle_host::sweep::run::{ERROR_TXT, point_dir};

mod chart;

/// The collected table's file name.
pub const COLLECTED_CSV: &str = "collected.csv";

/// One point as collected.
#[derive(Debug, Clone)]
struct Row {
    id: String,
    params: Vec<(String, Json)>,
    replica: Option<u64>,
    status: &'static str,
    summary: Option<Json>,
    error: Option<String>,
    series: Vec<Observables>,
    case: Option<&'static str>,
}

/// A point not done.
#[derive(Debug, Clone)]
pub struct Problem {
    /// Its index in the sweep.
    pub index: usize,
    /// Its id.
    pub id: String,
    /// Its status.
    pub status: &'static str,
    /// Why.
    pub why: String,
}

impl Problem {
    /// Whether running the sweep again runs it (`stopped_early` ends the same way
    /// again; a `foreign` folder is left alone; a `running` one is being run).
    pub fn reruns(&self) -> bool {
        matches!(self.status, "unfinished" | "missing" | "error" | "corrupt")
    }
}

/// What `collect` found.
#[derive(Debug, Clone)]
pub struct Collected {
    /// `collected.csv`.
    pub csv: PathBuf,
    /// Points.
    pub points: usize,
    /// Points not done.
    pub problems: Vec<Problem>,
    /// The chart drawn, if asked.
    pub chart: Option<PathBuf>,
}

fn number(v: Option<&Json>) -> String {
    match v {
        Some(Json::Number(n)) if n.is_f64() => n.as_f64().map(format_f64).unwrap_or_default(),
        Some(Json::Number(n)) => n.to_string(),
        Some(Json::String(s)) => s.clone(),
        Some(Json::Bool(b)) => b.to_string(),
        Some(Json::Null) | None => String::new(),
        Some(other) => other.to_string(),
    }
}

fn read_point(dir: &Path, record: &Json, figure1: &[(&'static str, Scene)]) -> Result<Row> {
    let id = record["id"]
        .as_str()
        .context("a point without id in sweep.json")?;
    let pdir = point_dir(dir, id);
    let params: Vec<(String, Json)> = record["parameters"]
        .as_object()
        .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
        .unwrap_or_default();
    let summary: Option<Json> = std::fs::read_to_string(pdir.join(SUMMARY_JSON))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let mut error = std::fs::read_to_string(pdir.join(ERROR_TXT)).ok();
    // A summary vouches for the files it records (older summaries record none).
    let corrupt = summary.as_ref().and_then(|s| {
        let files = s.get("files")?;
        match serde_json::from_value::<BTreeMap<String, FileCheck>>(files.clone()) {
            Ok(files) => mismatch(&pdir, &files),
            Err(e) => Some(format!("{}: unreadable files record: {e}", SUMMARY_JSON)),
        }
    });
    // The folder is the point's when its scene is the one the sweep recorded.
    let foreign = record["scene_toml_fnv1a64"].as_str().and_then(|want| {
        let found = std::fs::read(pdir.join(SCENE_TOML)).ok()?;
        let found = fnv1a64(&found);
        (found != want).then(|| {
            format!(
                "{}: digest {found} where {SWEEP_JSON} records {want}: another sweep's or a resumed run's scene",
                pdir.join(SCENE_TOML).display()
            )
        })
    });
    let status = match (&summary, &error) {
        _ if foreign.is_some() => "foreign",
        (Some(_), _) if corrupt.is_some() => "corrupt",
        (Some(s), _) if s["failure"].is_null() => "done",
        (Some(_), _) => "stopped_early",
        (None, Some(_)) => "error",
        (None, None) if pdir.join(CHECKPOINT).is_file() => "unfinished",
        _ => "missing",
    };
    // A point whose run is under way: its files are in between, and it is not to be
    // submitted again. A finished point is done even while a process looks at it.
    let status = match status {
        "done" | "foreign" => status,
        _ if FolderLock::held(&pdir).unwrap_or(false) => "running",
        s => s,
    };
    if foreign.is_some() {
        error = foreign;
    } else if corrupt.is_some() {
        error = corrupt;
    }
    let mut series = Vec::new();
    let mut case = None;
    if summary.is_some() && !matches!(status, "corrupt" | "foreign") {
        let scene = Scene::from_path(&pdir.join(SCENE_TOML)).ok();
        case = scene.and_then(|s| {
            let h = s.helix?;
            figure1
                .iter()
                .find(|(_, f)| f.helix == Some(h))
                .map(|(c, _)| *c)
        });
        if case.is_some() {
            let path = pdir.join(OBSERVABLES_CSV);
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("reading {}", path.display()))?;
            for (k, line) in text.lines().enumerate().skip(1) {
                series
                    .push(Observables::from_row(line).with_context(|| {
                        format!("{}:{}: unreadable row", path.display(), k + 1)
                    })?);
            }
        }
    }
    Ok(Row {
        id: id.to_string(),
        params,
        replica: record["replica"].as_u64(),
        status,
        summary,
        error,
        series,
        case,
    })
}

fn front(summary: &Json) -> Front {
    let f = &summary["front"];
    Front {
        cos_min: f["cos_min"].as_f64().unwrap_or(0.0),
        count: f["count"].as_u64().unwrap_or(0) as usize,
        correlation: f["correlation"].as_f64().unwrap_or(0.0),
        first_vertical: f["first_vertical"]
            .as_array()
            .map(|a| a.iter().map(Json::as_f64).collect())
            .unwrap_or_default(),
    }
}

/// The claims of each Figure 1 point, by claim id.
fn verdicts(rows: &[Row]) -> Vec<BTreeMap<&'static str, &'static str>> {
    // Points that differ only in their helix are the cases of one setting.
    let setting = |r: &Row| -> String {
        let rest: Vec<String> = r
            .params
            .iter()
            .filter(|(k, _)| !k.starts_with("helix."))
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        rest.join(",")
    };
    let fronts: Vec<Option<Front>> = rows.iter().map(|r| r.summary.as_ref().map(front)).collect();
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            let mut out = BTreeMap::new();
            let (Some(case), Some(f)) = (r.case, &fronts[i]) else {
                return out;
            };
            let mine = setting(r);
            let mut runs = vec![CaseRun {
                case,
                series: &r.series,
                front: f,
            }];
            for (j, other) in rows.iter().enumerate() {
                if let (Some(c), Some(fj)) = (other.case, &fronts[j])
                    && c != case
                    && !runs.iter().any(|x| x.case == c)
                    && setting(other) == mine
                {
                    runs.push(CaseRun {
                        case: c,
                        series: &other.series,
                        front: fj,
                    });
                }
            }
            for c in claims(&runs).into_iter().filter(|c| c.case == case) {
                if let Some(spec) = SPECS.iter().find(|s| s.id == c.id) {
                    out.insert(spec.id, c.verdict.name());
                }
            }
            out
        })
        .collect()
}

/// Merges the points of the sweep in `dir` into `DIR/collected.csv` and, with
/// `chart = Some((key, column))`, draws `DIR/<column>_vs_<key>.png`.
pub fn collect(dir: &Path, chart: Option<(&str, &str)>) -> Result<Collected> {
    let path = dir.join(SWEEP_JSON);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("reading {} (run `host-demo sweep` first)", path.display()))?;
    let record: Json =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let keys: Vec<String> = record["keys"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|k| k.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let replicas = record["replicas"].as_u64().unwrap_or(1) > 1;
    let figure1 = Scene::figure1()?;
    let rows: Vec<Row> = record["points"]
        .as_array()
        .context("sweep.json without points")?
        .iter()
        .map(|p| read_point(dir, p, &figure1))
        .collect::<Result<_>>()?;
    let verdicts = verdicts(&rows);
    let observables: Vec<&str> = COLUMNS[1..COLUMNS.len() - 1].to_vec();
    let mut header: Vec<String> = vec!["id".into(), "index".into()];
    header.extend(keys.iter().cloned());
    if replicas {
        header.push("replica".into());
    }
    header.extend(["status", "steps", "steps_done", "outcome"].map(String::from));
    header.extend(observables.iter().map(|c| c.to_string()));
    header.push("state".into());
    header.extend(["twist_rate", "front_correlation", "mean_iterations"].map(String::from));
    header.extend(SPECS.iter().map(|s| format!("claim_{}", s.id)));
    header.extend(["failure", "wall_time_s", "steps_per_second"].map(String::from));
    let csv_path = dir.join(COLLECTED_CSV);
    let mut csv = CsvWriter::new(AtomicFile::create(&csv_path)?, &header)?;
    let mut table: Vec<Vec<String>> = Vec::new();
    let mut problems = Vec::new();
    for (k, (r, v)) in rows.iter().zip(&verdicts).enumerate() {
        let s = r.summary.as_ref();
        let get = |key: &str| number(s.and_then(|s| s.get(key)));
        let fin = |key: &str| number(s.and_then(|s| s["final_observables"].get(key)));
        let mut row = vec![r.id.clone(), k.to_string()];
        for key in &keys {
            let v = r.params.iter().find(|(p, _)| p == key).map(|(_, v)| v);
            row.push(number(v));
        }
        if replicas {
            row.push(r.replica.map_or(String::new(), |x| x.to_string()));
        }
        row.extend([
            r.status.to_string(),
            get("steps"),
            get("steps_done"),
            get("outcome"),
        ]);
        for c in &observables {
            row.push(match *c {
                "com_x" | "com_y" | "com_z" => {
                    let i = usize::from(c.as_bytes()[4] - b'x');
                    number(s.and_then(|s| s["final_observables"]["com"].get(i)))
                }
                c => fin(c),
            });
        }
        row.push(fin("state"));
        row.push(get("twist_rate"));
        row.push(number(s.and_then(|s| s["front"].get("correlation"))));
        row.push(get("mean_iterations"));
        row.extend(
            SPECS
                .iter()
                .map(|spec| v.get(spec.id).map_or(String::new(), |x| x.to_string())),
        );
        let why = match r.status {
            "error" | "corrupt" | "foreign" => {
                r.error.clone().unwrap_or_default().trim().to_string()
            }
            "running" => "a live process holds the point's lock: collect again when it ends".into(),
            _ => get("failure"),
        };
        row.extend([why.clone(), get("wall_time_s"), get("steps_per_second")]);
        if r.status != "done" {
            problems.push(Problem {
                index: k,
                id: r.id.clone(),
                status: r.status,
                why,
            });
        }
        csv.write_record(&row)?;
        table.push(row);
    }
    csv.into_inner().commit()?;
    let chart = match chart {
        Some((x, y)) => Some(chart::draw(dir, &header, &table, x, y, replicas)?),
        None => None,
    };
    Ok(Collected {
        csv: csv_path,
        points: rows.len(),
        problems,
        chart,
    })
}
