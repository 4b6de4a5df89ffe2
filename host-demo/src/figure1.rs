//! The paper's Figure 1: three helical chains settling, run in parallel, drawn like the
//! paper's figure, and summarised in `figure1.json`.

use std::path::Path;

use anyhow::Result;
use rayon::prelude::*;
use serde::Serialize;

use crate::output::write_json;
use crate::render::{Figure1Case, draw_figure1};
use crate::scene::Scene;
use crate::sim::{RunOptions, RunResult, run};

/// One case's line of `figure1.json`.
#[derive(Debug, Clone, Serialize)]
pub struct CaseSummary {
    /// "a", "b" or "c".
    pub case: String,
    /// Bond length over the sum of radii.
    pub dhat: f64,
    /// Head radius over tail radius.
    pub head_ratio: f64,
    /// Final extension.
    pub extension: f64,
    /// Final verticality.
    pub verticality: f64,
    /// Late twist rate (rad per time unit).
    pub twist_rate: f64,
    /// Final head settling speed.
    pub head_speed: f64,
    /// Classified outcome.
    pub outcome: String,
    /// Time to reach extension 0.95 (None if never).
    pub time_to_stretch: Option<f64>,
    /// Simulated time.
    pub duration: f64,
    /// Wall time of the run, seconds.
    pub wall_time_s: f64,
    /// Failure, if the run stopped early.
    pub failure: Option<String>,
}

/// `figure1.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Figure1Summary {
    /// The three cases.
    pub cases: Vec<CaseSummary>,
    /// Wall time of the three runs together (they run in parallel), seconds.
    pub wall_time_s: f64,
}

fn title(case: &str, s: &Scene) -> String {
    let h = s.helix.as_ref();
    let dhat = h.map_or(0.0, |h| h.dhat);
    let ratio = h.map_or(0.0, |h| h.head_ratio);
    let head = if (ratio - 2f64.powf(1.0 / 3.0)).abs() < 1e-9 {
        "2^(1/3)".to_string()
    } else {
        format!("{ratio}")
    };
    format!("({case}) D={dhat:.2}, head {head}")
}

/// Summarises one run.
pub fn summarise(case: &str, scene: &Scene, r: &RunResult) -> CaseSummary {
    let h = scene.helix.as_ref();
    let f = &r.summary.final_observables;
    CaseSummary {
        case: case.to_string(),
        dhat: h.map_or(0.0, |h| h.dhat),
        head_ratio: h.map_or(0.0, |h| h.head_ratio),
        extension: f.extension,
        verticality: f.verticality,
        twist_rate: r.summary.twist_rate,
        head_speed: f.head_speed,
        outcome: r.summary.outcome.clone(),
        time_to_stretch: r
            .series
            .iter()
            .find(|o| o.extension >= 0.95)
            .map(|o| o.time),
        duration: f.time,
        wall_time_s: r.summary.wall_time_s,
        failure: r.summary.failure.clone(),
    }
}

/// Runs the three cases into `out/{a,b,c}` and writes `figure1.png` and `figure1.json`.
/// `max_steps` caps each run (a quick smoke run).
pub fn figure1(out: &Path, max_steps: Option<usize>) -> Result<Figure1Summary> {
    std::fs::create_dir_all(out)?;
    let scenes = Scene::figure1()?;
    let start = std::time::Instant::now();
    let opts = RunOptions {
        progress: true,
        max_steps,
        ..RunOptions::default()
    };
    let results: Vec<Result<RunResult>> = scenes
        .par_iter()
        .map(|(case, scene)| run(scene, case, Some(&out.join(case)), opts))
        .collect();
    let wall = start.elapsed().as_secs_f64();
    let mut cases = Vec::new();
    let mut panels = Vec::new();
    for ((case, scene), r) in scenes.iter().zip(results) {
        let r = r?;
        cases.push(summarise(case, scene, &r));
        panels.push(Figure1Case {
            title: match max_steps {
                Some(m) => format!("{} [QUICK: {m} steps at most]", title(case, scene)),
                None => title(case, scene),
            },
            initial: r.initial.clone(),
            last: r.last.clone(),
        });
    }
    draw_figure1(&out.join("figure1.png"), &panels)?;
    let summary = Figure1Summary {
        cases,
        wall_time_s: wall,
    };
    write_json(&out.join("figure1.json"), &summary)?;
    Ok(summary)
}
