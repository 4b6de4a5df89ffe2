//! The paper's Figure 1: three helical chains settling, run in parallel, drawn like the
//! paper's figure (and in more pictures: [`crate::pictures`]), and summarised in
//! `figure1.json`: per case the final numbers and the outcome timeline, and the
//! paper's claims with their verdicts ([`crate::claims`]).

use std::path::Path;

use anyhow::Result;
use rayon::prelude::*;
use serde::Serialize;

use crate::claims::{CaseRun, Claim, claims};
use crate::pictures::{self, ANIMATION_FRAMES, check_times, figure1_pictures};
use crate::timeline::{Segment, segments};
use hydrorattle::observables::FrameState;
use hydrorattle_host::output::write_json;
use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::{Front, KeepFrames, RunOptions, RunResult, run};

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
    /// Late state: the named state of most frames in the last quarter (or "failed").
    pub outcome: String,
    /// The named state over time, in segments of one state.
    pub timeline: Vec<Segment>,
    /// The order in which bonds first turned near-vertical.
    pub front: Front,
    /// Time to reach extension 0.95 (None if never).
    pub time_to_stretch: Option<f64>,
    /// Simulated time.
    pub duration: f64,
    /// Wall time of the run, seconds.
    pub wall_time_s: f64,
    /// Failure, if the run stopped early.
    pub failure: Option<String>,
    /// With a wall: the landing time, the end of the first step after which a sphere
    /// was held on the wall (its first contact); `None` if it never landed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub landing_time: Option<f64>,
    /// With a wall: the final state on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub on_wall: Option<OnWall>,
}

/// A case's final state on the wall.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct OnWall {
    /// Spheres in contact with the wall at the end.
    pub contacts: u32,
    /// Smallest sphere-wall gap at the end (0 at contact).
    pub gap: f64,
    /// Centre of mass's height above the wall at the end.
    pub com_height: f64,
}

/// `figure1.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Figure1Summary {
    /// Every state name, in a fixed order (for legends).
    pub states: Vec<&'static str>,
    /// The wall's height (`figure1 --wall`), if there was one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_height: Option<f64>,
    /// The three cases.
    pub cases: Vec<CaseSummary>,
    /// The paper's claims, with verdicts computed from the runs.
    pub claims: Vec<Claim>,
    /// Wall time of the three runs together (they run in parallel), seconds.
    pub wall_time_s: f64,
    /// Wall time of drawing every picture (in parallel), seconds.
    pub drawing_wall_time_s: f64,
    /// One line per picture written.
    #[serde(skip)]
    pub pictures: Vec<String>,
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
        timeline: segments(&r.series),
        front: r.summary.front.clone(),
        time_to_stretch: r
            .series
            .iter()
            .find(|o| o.extension >= 0.95)
            .map(|o| o.time),
        duration: f.time,
        wall_time_s: r.summary.wall_time_s,
        failure: r.summary.failure.clone(),
        landing_time: r.summary.landing_time,
        on_wall: match (f.wall_contacts, f.wall_gap, f.wall_height) {
            (Some(contacts), Some(gap), Some(com_height)) => Some(OnWall {
                contacts,
                gap,
                com_height,
            }),
            _ => None,
        },
    }
}

/// The claims of the three cases' runs (`scenes` as from `Scene::figure1`, results in
/// the same order).
pub fn claims_of(scenes: &[(&str, Scene)], results: &[RunResult]) -> Vec<Claim> {
    let runs: Vec<CaseRun<'_>> = scenes
        .iter()
        .zip(results)
        .map(|((case, _), r)| CaseRun {
            case,
            series: &r.series,
            front: &r.summary.front,
        })
        .collect();
    claims(&runs)
}

/// Runs the three cases into `out/{a,b,c}` and writes `figure1.json` and the pictures
/// ([`crate::pictures`]). `max_steps` caps each run (a quick smoke run).
pub fn figure1(out: &Path, max_steps: Option<usize>) -> Result<Figure1Summary> {
    figure1_at(out, max_steps, &[])
}

/// [`figure1`], with `snapshots.png` at the times `at` (none: no such file); times are
/// checked (finite, within the runs' duration) before anything runs.
pub fn figure1_at(out: &Path, max_steps: Option<usize>, at: &[f64]) -> Result<Figure1Summary> {
    figure1_wall(out, max_steps, at, None)
}

/// [`figure1_at`] with the three chains above a wall at height `wall` (`figure1
/// --wall H`): each lands on it; `figure1.json` gives each case's landing time and its
/// final state on the wall, and the pictures show the landed chains.
pub fn figure1_wall(
    out: &Path,
    max_steps: Option<usize>,
    at: &[f64],
    wall: Option<f64>,
) -> Result<Figure1Summary> {
    figure1_near(out, max_steps, at, wall, None)
}

/// [`figure1_wall`] with Stokesian dynamics' near field on every chain (`figure1
/// --near-field`; `docs/NEAR.md`): the same runs on the top rung of the model ladder.
pub fn figure1_near(
    out: &Path,
    max_steps: Option<usize>,
    at: &[f64],
    wall: Option<f64>,
    near: Option<hydrorattle_host::scene::NearField>,
) -> Result<Figure1Summary> {
    let mut scenes = Scene::figure1()?;
    if let Some(n) = near {
        for (case, scene) in scenes.iter_mut() {
            *scene = scene
                .clone()
                .with_near_field(n)
                .map_err(|e| anyhow::anyhow!("--near-field, case ({case}): {e}"))?;
        }
    }
    if let Some(h) = wall {
        for (case, scene) in scenes.iter_mut() {
            *scene = scene
                .clone()
                .with_wall(h)
                .map_err(|e| anyhow::anyhow!("--wall {h}, case ({case}): {e}"))?;
        }
    }
    let duration = scenes
        .iter()
        .map(|(_, s)| s.integrator.duration)
        .fold(f64::INFINITY, f64::min);
    check_times(at, duration)?;
    std::fs::create_dir_all(out)?;
    let start = std::time::Instant::now();
    let results: Vec<Result<RunResult>> = scenes
        .par_iter()
        .map(|(case, scene)| {
            let steps = max_steps.map_or(scene.integrator.steps(), |m| {
                m.min(scene.integrator.steps())
            });
            let opts = RunOptions {
                progress: true,
                max_steps,
                keep: KeepFrames {
                    every: Some((steps / ANIMATION_FRAMES).max(1)),
                    at,
                },
                ..RunOptions::default()
            };
            run(scene, case, Some(&out.join(case)), opts)
        })
        .collect();
    let elapsed = start.elapsed().as_secs_f64();
    let results: Vec<RunResult> = results.into_iter().collect::<Result<_>>()?;
    let mut cases = Vec::new();
    let mut titles = Vec::new();
    let mut runs = Vec::new();
    for ((case, scene), r) in scenes.iter().zip(results) {
        cases.push(summarise(case, scene, &r));
        titles.push(match max_steps {
            Some(m) => format!("{} [QUICK: {m} steps at most]", title(case, scene)),
            None => title(case, scene),
        });
        runs.push(r);
    }
    let case_runs: Vec<pictures::CaseRun<'_>> = scenes
        .iter()
        .zip(&titles)
        .zip(&runs)
        .map(|(((case, _), title), result)| pictures::CaseRun {
            case,
            title,
            result,
        })
        .collect();
    let (pictures, drawing) = figure1_pictures(out, &case_runs, at)?;
    log::info!("figure 1 pictures drawn in {drawing:.3} s");
    let summary = Figure1Summary {
        states: FrameState::ALL.iter().map(|s| s.name()).collect(),
        wall_height: wall,
        cases,
        claims: claims_of(&scenes, &runs),
        wall_time_s: elapsed,
        drawing_wall_time_s: drawing,
        pictures,
    };
    write_json(&out.join("figure1.json"), &summary)?;
    Ok(summary)
}
